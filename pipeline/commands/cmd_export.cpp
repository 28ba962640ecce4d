// SPDX-License-Identifier: BSD-3-Clause
// lidarcal export model.json --format yaml|lut [-o FILE] [--step S] [--sensor NAME]

#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "common/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/model_io.hpp"
#include "io/rig_model_io.hpp"
#include "pipeline/commands/cli_options.hpp"
#include "pipeline/commands/commands.hpp"
#include "pipeline/stages/model_export.hpp"
#include "pipeline/stages/stages.hpp"

namespace lidarcal::pipeline {

void addExportCommand(CLI::App& app) {
  struct Options {
    std::string model, format, out, sensor;
    double step_m = 0.001;
    bool overwrite = false;
  };
  auto o = std::make_shared<Options>();
  auto c = std::make_shared<CorrectionOptions>();
  CLI::App* sub = app.add_subcommand("export",
                                     "Write a model.json for a ROS driver: ROS parameters (yaml) "
                                     "or a lookup table reading -> range (lut)");
  sub->add_option("MODEL", o->model, "model.json from lidarcal calibrate")->required();
  sub->add_option("--format", o->format,
                  "yaml: ROS parameter file (bias polynomial, the readings it corrects, "
                  "inversion); lut: CSV "
                  "reading_m,range_m over those readings, each row what `lidarcal correct` gives")
      ->check(CLI::IsMember({"yaml", "lut"}))
      ->required();
  sub->add_option("-o,--out", o->out, "Output file (default: standard output)");
  sub->add_option("--step", o->step_m, "lut: reading step, metres")->capture_default_str();
  sub->add_option("--sensor", o->sensor,
                  "With a rig model (several sensors, from `calibrate RIG`): the block to export, "
                  "by sensor name, topic or frame");
  addCorrectionOptions(sub, c);
  sub->add_flag("--overwrite", o->overwrite, "Replace the output file if it exists");
  sub->callback([o, c, sub] {
    if (o->format != "lut" && sub->count("--step") > 0)
      throw InputError("", "--step", "applies to --format lut only", "drop --step");
    if (!o->out.empty()) io::checkOutputFile(o->out, o->overwrite);
    std::string sensor;  // the rig's block chosen, empty for a single sensor's model
    const CalibrationModel model = io::readModelFor(o->model, o->sensor, &sensor);
    ExportConfig config;
    config.inversion = c->method();
    config.outside = c->outsidePolicy();
    config.step_m = o->step_m;
    config.source = sensor.empty() ? o->model : o->model + " (sensor " + sensor + ")";
    checkModelInvertible(model, config.source, config.outside);
    // refuses ml without the squared law
    modelCorrector(model, config.inversion, config.outside, config.source);
    const std::string text =
        o->format == "yaml" ? exportYaml(model, config) : exportLut(model, config);
    if (o->out.empty()) {
      std::fwrite(text.data(), 1, text.size(), stdout);
      return;
    }
    io::writeTextAtomically(o->out, text);
  });
}

}  // namespace lidarcal::pipeline
