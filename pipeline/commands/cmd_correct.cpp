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
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/cmd_rig.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/commands/progress.hpp"
#include "pipeline/reports/model_text.hpp"
#include "pipeline/reports/papers.hpp"
#include "pipeline/reports/words.hpp"
#include "pipeline/stages/bag2_correct.hpp"
#include "pipeline/stages/bag_correct.hpp"
#include "pipeline/stages/rig_correct.hpp"
#include "pipeline/stages/stages.hpp"

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

/// The command line of `correct`.
struct CorrectOptions {
  std::string seq, model, out, topic, sensor;
  bool ascii = false, overwrite = false, force = false;
  int threads = 0;
};

/// The model for a bag's topic (ROS 1 or ROS 2), checked against the sensor facts the bag
/// records (a warning with --force), and its corrector.
struct BagModel {
  CalibrationModel model;
  calibration::Outside outside;
  calibration::ReadingCorrector correct;
};

BagModel bagModel(const CorrectOptions& o, const CorrectionOptions& c, bool ros2) {
  CalibrationModel model = io::readModelFor(o.model, o.sensor.empty() ? o.topic : o.sensor);
  const calibration::Outside outside = c.outsidePolicy();
  const SensorFacts facts =
      ros2 ? rosbag2SensorFacts(o.seq, o.topic) : bagSensorFacts(o.seq, o.topic);
  if (const std::string w = checkModelFitsSensor(model, facts, o.model, o.force, outside);
      !w.empty())
    std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
  calibration::ReadingCorrector correct = modelCorrector(model, c.method(), outside, o.model);
  return {std::move(model), outside, std::move(correct)};
}

/// correct IN.bag --out OUT.bag: every message copied, the topic's ranges corrected.
void correctBag(const CorrectOptions& o, const CorrectionOptions& c) {
  checkBagOutputKind(o.seq, o.out, true);
  io::requireRosbagSupport(o.seq);
  io::checkOutsideInput(o.seq, o.out);
  io::checkOutputFile(o.out, o.overwrite);
  const BagModel m = bagModel(o, c, false);
  CorrectionStats stats;
  io::writeAtomically(o.out, [&](const std::filesystem::path& tmp) {
    stats = correctRosbag(o.seq, tmp, o.topic, m.model, m.correct, o.model);
  });
  printStats(stats, o.out, m.model, m.outside);
}

/// correct IN.mcap|IN.db3|IN_DIR --out the same kind: every message copied, the topic's ranges
/// corrected.
void correctBag2(const CorrectOptions& o, const CorrectionOptions& c) {
  checkBagOutputKind(o.seq, o.out, false);
  io::checkOutsideInput(o.seq, o.out);
  std::error_code ec;
  const bool dir = std::filesystem::is_directory(o.seq, ec);
  if (!dir) io::checkOutputFile(o.out, o.overwrite);
  const BagModel m = bagModel(o, c, true);
  CorrectionStats stats;
  if (dir) {
    io::StagedDirectory staged(o.out, o.overwrite);
    stats = correctRosbag2(o.seq, staged.path(), o.topic, m.model, m.correct, o.model);
    staged.commit();
  } else {
    io::writeAtomically(o.out, [&](const std::filesystem::path& tmp) {
      stats = correctRosbag2(o.seq, tmp, o.topic, m.model, m.correct, o.model);
    });
  }
  printStats(stats, o.out, m.model, m.outside);
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
void correctRigBag(const CorrectOptions& o, const CorrectionOptions& c, bool ros2) {
  const std::string &in = o.seq, &out = o.out, &model_file = o.model;
  const bool overwrite = o.overwrite, force = o.force;
  std::vector<std::string> keys = splitList(o.sensor);
  for (const std::string& t : splitList(o.topic)) keys.push_back(t);
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
    done = correctRigRosbag(
        in, tmp,
        RigBagCorrection{model, model_file, blocks, c.method(), c.outsidePolicy(), force, ros2},
        warnings);
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
  auto o = std::make_shared<CorrectOptions>();
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
      if (io::isRigModel(o->model)) return correctRigBag(*o, *c, ros2);
      return ros1 ? correctBag(*o, *c) : correctBag2(*o, *c);
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
    const SequenceCorrection how{c->method(), outside,
                                 o->ascii ? io::PcdEncoding::ascii : io::PcdEncoding::binary,
                                 o->threads};
    const auto stats = correctSequence(
        seq, model, out.path(), how, [&](std::size_t done, std::size_t) { progress.update(done); });
    progress.finish();
    out.commit();
    printStats(stats, o->out, model, outside);
  });
}

}  // namespace lidarcal::pipeline
