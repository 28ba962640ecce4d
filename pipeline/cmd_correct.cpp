// lidarcal correct SEQ --model model.json --out OUT

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/papers.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/stages.hpp"
#include "pipeline/words.hpp"

namespace lidarcal::pipeline {

void addCorrectCommand(CLI::App& app) {
  struct Options {
    std::string seq, model, out, inversion = "ls", outside = "keep";
    bool ascii = false, overwrite = false, force = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand("correct", "Rewrite every scan of a sequence with calibrated ranges");
  sub->add_option("SEQ", o->seq, "Sequence directory (any sequence of the calibrated sensor)")->required();
  sub->add_option("--model", o->model, "model.json from lidarcal calibrate")->required();
  sub->add_option("-o,--out", o->out, "Output sequence directory")->required();
  sub->add_option("--inversion", o->inversion,
                  "ls: the distance whose f equals the reading (" + std::string(papers::kTriangulation) +
                      ", eq. 30); ml: the most likely distance (eq. 28, squared noise law only)")
      ->check(CLI::IsMember({"ls", "ml"}))
      ->capture_default_str();
  sub->add_option("--outside", o->outside,
                  "Readings outside the range the model was fitted over (model.json fitted_range): keep them as they "
                  "are, extrapolate the polynomial, or drop them (no return)")
      ->check(CLI::IsMember({"keep", "extrapolate", "drop"}))
      ->capture_default_str();
  sub->add_flag("--ascii", o->ascii, "Write ASCII PCD instead of binary");
  sub->add_flag("--overwrite", o->overwrite, "Replace OUT if it exists");
  sub->add_flag("--force", o->force,
                "Apply a model whose range limits differ from the sequence's (same sensor, other limits set), with a "
                "warning");
  sub->callback([o] {
    io::checkOutsideInput(o->seq, o->out);
    const io::Sequence seq = io::openSequence(o->seq);
    const CalibrationModel model = io::readModel(o->model);
    calibration::Outside outside = calibration::Outside::keep;
    calibration::parseOutside(o->outside, outside);
    if (const std::string w = checkModelFits(model, seq, o->model, o->force, outside); !w.empty())
      std::fprintf(stderr, "lidarcal: warning: %s\n", w.c_str());
    if (const auto [fewest, most] = io::pointCountRange(seq); fewest != most)
      std::fprintf(stderr,
                   "lidarcal: warning: %s: the number of points per scan varies from %zu to %zu; each point is corrected "
                   "along its own beam, so this does not matter unless the scans come from different sensors\n",
                   o->seq.c_str(), fewest, most);
    io::StagedDirectory out(o->out, o->overwrite);
    Progress progress("correct", seq.scans.size());
    const auto stats = correctSequence(
        seq, model, o->inversion == "ml" ? calibration::InversionMethod::ml : calibration::InversionMethod::ls, out.path(),
        o->ascii ? io::PcdEncoding::ascii : io::PcdEncoding::binary,
        [&](std::size_t done, std::size_t) { progress.update(done); }, outside);
    progress.finish();
    out.commit();
    if (!quiet())
      std::fprintf(stderr, "corrected %s in %s into %s (%zu without a distance in the window)\n",
                   plural(stats.corrected, "return").c_str(), plural(stats.scans, "scan").c_str(), o->out.c_str(),
                   stats.unresolved);
    if (stats.outside > 0 && !quiet())
      std::fprintf(stderr, "%zu returns lie outside the readings the model was fitted on (%s): %s (--outside)\n",
                   stats.outside, o->model.c_str(), outside == calibration::Outside::drop ? "dropped" : "kept as they are");
  });
}

}  // namespace lidarcal::pipeline
