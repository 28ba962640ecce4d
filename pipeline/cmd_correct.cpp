// SPDX-License-Identifier: BSD-3-Clause
// lidarcal correct SEQ --model model.json --out OUT
// lidarcal correct IN.bag --model model.json --out OUT.bag [--topic T]
// lidarcal correct IN.mcap|IN.db3|IN_DIR --model model.json --out OUT.mcap|OUT.db3|OUT_DIR [--topic
// T] lidarcal correct IN.bag|IN.mcap|IN.db3|IN_DIR --model RIG_MODEL.json --out OUT [--sensor A,B]

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/detect_format.hpp"
#include "io/import_rosbag.hpp"
#include "io/import_rosbag2.hpp"
#include "io/model_io.hpp"
#include "io/rig_model_io.hpp"
#include "pipeline/bag2_correct.hpp"
#include "pipeline/bag_correct.hpp"
#include "pipeline/cli_options.hpp"
#include "pipeline/cmd_rig.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/model_text.hpp"
#include "pipeline/papers.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/rig_correct.hpp"
#include "pipeline/stages.hpp"
#include "pipeline/words.hpp"

namespace lidarcal::pipeline {

namespace {

bool isRosbag(const std::string& input) {
  std::error_code ec;
  return std::filesystem::is_regular_file(input, ec) &&
         io::detectRecordingFormat(input).kind == io::RecordingKind::rosbag1;
}

/// A ROS 2 bag: an MCAP or rosbag2 SQLite file, or a directory with metadata.yaml.
bool isRosbag2(const std::string& input) {
  std::error_code ec;
  if (std::filesystem::is_directory(input, ec))
    return std::filesystem::is_regular_file(std::filesystem::path(input) / "metadata.yaml", ec);
  if (!std::filesystem::is_regular_file(input, ec)) return false;
  const io::RecordingKind kind = io::detectRecordingFormat(input).kind;
  return kind == io::RecordingKind::mcap || kind == io::RecordingKind::rosbag2;
}

/// A missing path named like a bag file (.bag, .mcap, .db3) is a missing file, not a missing
/// sequence directory: throws InputError saying so.
void checkBagFileExists(const std::string& input) {
  const std::string ext = std::filesystem::path(input).extension().string();
  std::error_code ec;
  if ((ext == ".bag" || ext == ".mcap" || ext == ".db3") && !std::filesystem::exists(input, ec))
    throw InputError(input, "", "file does not exist", "check the path");
}

void printStats(const CorrectionStats& stats, const std::string& out, const CalibrationModel& model,
                calibration::Outside outside) {
  if (quiet()) return;
  std::fprintf(stderr,
               "corrected %s in %s into %s: %zu inside the fitted range, %zu beyond it, %zu "
               "without a distance\n",
               plural(stats.corrected + stats.extrapolated, "return").c_str(),
               plural(stats.scans, "scan").c_str(), out.c_str(), stats.corrected,
               stats.extrapolated, stats.unresolved);
  if (const std::string beyond = beyondFitText(stats, model, outside); !beyond.empty())
    std::fprintf(stderr, "%s\n", beyond.c_str());
}

/// correct IN.bag --out OUT.bag: every message copied, the topic's ranges corrected.
void correctBag(const std::string& in, const std::string& model_file, const std::string& out,
                const std::string& topic, const CorrectionOptions& c, bool overwrite, bool force,
                const std::string& sensor) {
  checkBagOutputKind(in, out, true);
  io::requireRosbagSupport(in);
  io::checkOutsideInput(in, out);
  io::checkOutputFile(out, overwrite);
  const CalibrationModel model = io::readModelFor(model_file, sensor.empty() ? topic : sensor);
  const calibration::Outside outside = c.outsidePolicy();
  if (const std::string w =
          checkModelFitsSensor(model, bagSensorFacts(in, topic), model_file, force, outside);
      !w.empty())
    std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  const calibration::ReadingCorrector correct =
      modelCorrector(model, c.method(), outside, model_file);
  CorrectionStats stats;
  io::writeAtomically(out, [&](const std::filesystem::path& tmp) {
    stats = correctRosbag(in, tmp, topic, model, correct, model_file);
  });
  printStats(stats, out, model, outside);
}

/// correct IN.mcap|IN.db3|IN_DIR --out the same kind: every message copied, the topic's ranges
/// corrected.
void correctBag2(const std::string& in, const std::string& model_file, const std::string& out,
                 const std::string& topic, const CorrectionOptions& c, bool overwrite, bool force,
                 const std::string& sensor) {
  checkBagOutputKind(in, out, false);
  io::checkOutsideInput(in, out);
  std::error_code ec;
  const bool dir = std::filesystem::is_directory(in, ec);
  if (!dir) io::checkOutputFile(out, overwrite);
  const CalibrationModel model = io::readModelFor(model_file, sensor.empty() ? topic : sensor);
  const calibration::Outside outside = c.outsidePolicy();
  if (const std::string w =
          checkModelFitsSensor(model, rosbag2SensorFacts(in, topic), model_file, force, outside);
      !w.empty())
    std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  const calibration::ReadingCorrector correct =
      modelCorrector(model, c.method(), outside, model_file);
  CorrectionStats stats;
  if (dir) {
    io::StagedDirectory staged(out, overwrite);
    stats = correctRosbag2(in, staged.path(), topic, model, correct, model_file);
    staged.commit();
  } else {
    io::writeAtomically(out, [&](const std::filesystem::path& tmp) {
      stats = correctRosbag2(in, tmp, topic, model, correct, model_file);
    });
  }
  printStats(stats, out, model, outside);
}

/// The topics of a ROS1 or ROS 2 bag, of any type (the rewriter refuses a block's topic that is not
/// a LaserScan).
std::vector<std::string> bagTopicNames(const std::string& in, bool ros2) {
  std::vector<std::string> topics;
  for (const io::BagTopic& t : ros2 ? io::listRosbag2Topics(in) : io::listBagTopics(in))
    topics.push_back(t.topic);
  return topics;
}

/// correct IN.bag|IN.mcap|IN.db3|IN_DIR --model RIG_MODEL.json: each sensor's topic corrected by
/// its block, in one pass.
void correctRigBag(const std::string& in, const std::string& model_file, const std::string& out,
                   const std::vector<std::string>& keys, const CorrectionOptions& c, bool overwrite,
                   bool force, bool ros2) {
  checkBagOutputKind(in, out, !ros2);
  if (!ros2) io::requireRosbagSupport(in);
  io::checkOutsideInput(in, out);
  std::error_code ec;
  const bool dir = ros2 && std::filesystem::is_directory(in, ec);
  if (!dir) io::checkOutputFile(out, overwrite);
  const io::RigModel model = io::readRigModel(model_file);
  const std::vector<std::size_t> blocks =
      rigBlocksForBag(model, model_file, bagTopicNames(in, ros2), keys);
  std::vector<std::string> warnings;
  std::vector<RigCorrection> done;
  const auto write = [&](const std::filesystem::path& tmp) {
    done = correctRigRosbag(in, tmp, model, model_file, blocks, c.method(), c.outsidePolicy(),
                            force, ros2, warnings);
  };
  if (dir) {
    io::StagedDirectory staged(out, overwrite);
    write(staged.path());
    staged.commit();
  } else {
    io::writeAtomically(out, write);
  }
  for (const std::string& w : warnings) std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  for (const RigCorrection& d : done) {
    std::fprintf(stderr, "%s (%s): ", d.topic.c_str(), d.sensor.c_str());
    printStats(d.stats, out, model.sensors[*model.find(d.sensor)].model, c.outsidePolicy());
  }
}

}  // namespace

void addCorrectCommand(CLI::App& app) {
  struct Options {
    std::string seq, model, out, topic, sensor;
    bool ascii = false, overwrite = false, force = false;
    int threads = 0;
  };
  auto o = std::make_shared<Options>();
  auto c = std::make_shared<CorrectionOptions>();
  CLI::App* sub = app.add_subcommand("correct",
                                     "Rewrite every scan of a sequence (or every LaserScan of a "
                                     "ROS1 or ROS 2 bag) with calibrated ranges");
  sub->add_option("SEQ", o->seq,
                  "Sequence directory (any sequence of the calibrated sensor), a ROS1 bag, or a "
                  "ROS 2 bag (.mcap, .db3 or its directory)")
      ->required();
  sub->add_option("--model", o->model, "model.json from lidarcal calibrate")->required();
  sub->add_option(
         "-o,--out", o->out,
         "Output sequence directory; for a bag, a bag of the same kind (.bag, .mcap, .db3 or a "
         "directory): every message copied, only the corrected topics' ranges changed")
      ->required();
  addCorrectionOptions(sub, c);
  sub->add_option("--topic", o->topic,
                  "A bag's LaserScan topic to correct (default: the bag's only one)");
  sub->add_option("--sensor", o->sensor,
                  "With a rig model (several sensors): the blocks to apply, by sensor name, topic "
                  "or frame, several "
                  "comma-separated (a ROS1 or ROS 2 bag: default every block whose topic the bag "
                  "holds, each topic "
                  "corrected by its own block in one pass)");
  sub->add_flag("--ascii", o->ascii, "Write ASCII PCD instead of binary");
  addThreadsOption(sub, o->threads,
                   "correcting a sequence's scans side by side (a bag is corrected in order)");
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->add_flag("--force", o->force,
                "Apply a model whose range limits differ from the sequence's (same sensor, other "
                "limits set), with a "
                "warning");
  sub->callback([o, c, sub] {
    checkBagFileExists(o->seq);
    const bool ros1 = isRosbag(o->seq), ros2 = !ros1 && isRosbag2(o->seq);
    if (ros1 || ros2) {
      if (o->ascii)
        throw InputError("", "--ascii", "applies to sequences, not to bags", "drop --ascii");
      if (io::isRigModel(o->model)) {
        std::vector<std::string> keys = splitList(o->sensor);
        for (const std::string& t : splitList(o->topic)) keys.push_back(t);
        return correctRigBag(o->seq, o->model, o->out, keys, *c, o->overwrite, o->force, ros2);
      }
      if (ros1)
        return correctBag(o->seq, o->model, o->out, o->topic, *c, o->overwrite, o->force,
                          o->sensor);
      return correctBag2(o->seq, o->model, o->out, o->topic, *c, o->overwrite, o->force, o->sensor);
    }
    if (sub->count("--topic") > 0)
      throw InputError(o->seq, "--topic", "applies to bags only (this is not one)", "drop --topic");
    io::checkOutsideInput(o->seq, o->out);
    const io::Sequence seq = io::openSequence(o->seq);
    const CalibrationModel model = io::readModelFor(o->model, o->sensor);
    const calibration::Outside outside = c->outsidePolicy();
    if (const std::string w = checkModelFits(model, seq, o->model, o->force, outside); !w.empty())
      std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
    if (const auto [fewest, most] = io::pointCountRange(seq); fewest != most)
      std::fprintf(stderr,
                   "lidarcal: warning: %s: the number of points per scan varies from %zu to %zu; "
                   "each point is corrected "
                   "along its own beam, so this does not matter unless the scans come from "
                   "different sensors\n",
                   o->seq.c_str(), fewest, most);
    io::StagedDirectory out(o->out, o->overwrite);
    Progress progress("correct", seq.scans.size());
    const auto stats = correctSequence(
        seq, model, c->method(), out.path(),
        o->ascii ? io::PcdEncoding::ascii : io::PcdEncoding::binary,
        [&](std::size_t done, std::size_t) { progress.update(done); }, outside, o->threads);
    progress.finish();
    out.commit();
    printStats(stats, o->out, model, outside);
  });
}

}  // namespace lidarcal::pipeline
