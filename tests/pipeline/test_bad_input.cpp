// SPDX-License-Identifier: BSD-3-Clause
// The bad-input catalogue (docs/ERRORS.md), one row per case: every command that reads the
// input refuses it with the documented exit code and a message naming the file, the item and
// the remedy; the input is byte for byte unchanged and nothing is left at or beside the output
// path. Harness and how to add rows: bad_input_util.hpp.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bad_input_builders.hpp"
#include "bad_input_util.hpp"
#include "io/import_test_util.hpp"

namespace lidarcal {
namespace {

using namespace test;

using Commands = std::vector<std::pair<const char*, std::string>>;

// Commands that read a scan sequence, for the PCD and sequence cases.
const Commands kSequenceCommands = {
    {"info", "info {SEQ}"},
    {"detect", "detect {SEQ} --out {OUT}"},
    {"calibrate", "calibrate {SEQ} --out {OUT}"},
    {"correct", "correct {SEQ} --model {FIX}/model.json --out {OUT}"},
    {"run", "run {SEQ} --no-truth --out {OUT}"},
};

// Commands that write an output, with an input to read, for the output cases.
const Commands kWritingCommands = {
    {"detect", "detect {SEQ} --out {OUT}"},
    {"calibrate", "calibrate {SEQ} --out {OUT}"},
    {"correct", "correct {SEQ} --model {FIX}/model.json --out {OUT}"},
    {"run", "run {SEQ} --no-truth --out {OUT}"},
    {"simulate", "simulate --scene {IN}/scene.json --out {OUT} --stops 2 --scans-per-stop 2"},
    {"import", "import --from csv {IN}/scans.csv --out {OUT}"},
};

/// Inputs every writing command can read: the binary sequence, a scene and a CSV recording.
void writableInputs(const Ws& w) {
  copySequence(w);
  fs::copy_file(scenePath("paper_field.json"), w.in / "scene.json");
  std::string csv = "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n";
  for (int s = 0; s < 40; ++s)
    for (int b = 0; b < 360; ++b)
      csv += std::to_string(s) + ",0,0,0," + std::to_string(b * 0.0174533) + ",2.5\n";
  writeFile(w.in / "scans.csv", csv);
  writeFile(w.in / "file.txt", "a file where a directory is expected\n");
}

/// Adds one case per command: the same input, exit code and message parts, named `name`_command.
void forEach(std::vector<BadInputCase>& c, const Commands& commands, const std::string& name,
             std::function<void(const Ws&)> prepare, int code, std::vector<std::string> message) {
  for (const auto& [cmd, args] : commands) {
    BadInputCase k;
    k.name = name + "_" + cmd;
    k.args = args;
    k.prepare = prepare;
    k.exit_code = code;
    k.message = message;
    c.push_back(k);
  }
}

/// Scan files, for every command that reads a sequence.
void scanFileCases(std::vector<BadInputCase>& c) {
  forEach(c, kSequenceCommands, "pcd_truncated",
          withScan("scan_000001.pcd", [](std::string& b) { b.resize(b.size() - 100); }), 2,
          {"scan_000001.pcd", "DATA", "truncated"});
  forEach(c, kSequenceCommands, "pcd_truncated_ascii",
          [](const Ws& w) {
            copyAsciiSequence(w);
            editFile(w.seq() / "scan_000002.pcd", [](std::string& b) { b.resize(b.size() / 2); });
          },
          2, {"scan_000002.pcd", "DATA", "re-export the scan"});
  forEach(c, kSequenceCommands, "pcd_garbage",
          [](const Ws& w) {
            copySequence(w);
            std::string junk;
            std::uint32_t x = 12345;
            for (int i = 0; i < 5000; ++i)
              junk += static_cast<char>((x = x * 1103515245u + 12345u) >> 24);
            writeFile(w.seq() / "scan_000003.pcd", junk);
          },
          2, {"scan_000003.pcd", "header", "not a PCD file"});
  forEach(c, kSequenceCommands, "pcd_fields_without_xy",
          withScan("scan_000000.pcd",
                   [](std::string& b) { setHeaderLine(b, "FIELDS", "FIELDS a b z"); }),
          2, {"scan_000000.pcd", "FIELDS", "no 'x' field"});
  forEach(
      c, kSequenceCommands, "pcd_points_not_width_x_height",
      withScan("scan_000000.pcd", [](std::string& b) { setHeaderLine(b, "POINTS", "POINTS 361"); }),
      2, {"scan_000000.pcd", "POINTS", "differs from WIDTH x HEIGHT"});
  forEach(c, kSequenceCommands, "pcd_nan_in_one_coordinate",
          withScan("scan_000001.pcd",
                   [](std::string& b) { setFloat(b, firstReturn(b), 1, std::nanf("")); }),
          2,
          {"scan_000001.pcd", "point ", "only one of x, y is NaN",
           "without return must have x and y NaN"});
  forEach(c, kSequenceCommands, "pcd_infinite_coordinate",
          withScan("scan_000001.pcd",
                   [](std::string& b) {
                     setFloat(b, firstReturn(b), 0, std::numeric_limits<float>::infinity());
                   }),
          2, {"scan_000001.pcd", "point ", "infinite", "write NaN"});
  forEach(
      c, kSequenceCommands, "pcd_absurd_range",
      withScan("scan_000002.pcd", [](std::string& b) { setFloat(b, firstReturn(b), 0, 1e30f); }), 2,
      {"scan_000002.pcd", "point ", "beyond 100 km", "units"});
  forEach(c, kSequenceCommands, "viewpoint_missing",
          withScan("scan_000000.pcd", [](std::string& b) { setHeaderLine(b, "VIEWPOINT", ""); }), 2,
          {"scan_000000.pcd", "VIEWPOINT", "missing", "VIEWPOINT tx ty 0 qw 0 0 qz"});
  forEach(c, kSequenceCommands, "viewpoint_six_numbers",
          withScan("scan_000000.pcd",
                   [](std::string& b) { setHeaderLine(b, "VIEWPOINT", "VIEWPOINT 0 0 0 1 0 0"); }),
          2, {"scan_000000.pcd", "VIEWPOINT", "expected 7 numbers"});
  forEach(
      c, kSequenceCommands, "viewpoint_not_a_number",
      withScan("scan_000000.pcd",
               [](std::string& b) { setHeaderLine(b, "VIEWPOINT", "VIEWPOINT 0 0 0 one 0 0 0"); }),
      2, {"scan_000000.pcd", "VIEWPOINT", "'one' is not a finite number"});
  forEach(
      c, kSequenceCommands, "viewpoint_not_unit",
      withScan("scan_000000.pcd",
               [](std::string& b) { setHeaderLine(b, "VIEWPOINT", "VIEWPOINT 0 0 0 2 0 0 0"); }),
      2, {"scan_000000.pcd", "VIEWPOINT", "not of unit length"});
  forEach(c, kSequenceCommands, "viewpoint_roll",
          withScan("scan_000000.pcd",
                   [](std::string& b) {
                     setHeaderLine(b, "VIEWPOINT", "VIEWPOINT 0 0 0 0.7071068 0.7071068 0 0");
                   }),
          2, {"scan_000000.pcd", "VIEWPOINT", "roll/pitch"});
}

/// The sequence directory, for every command that reads one.
void sequenceDirectoryCases(std::vector<BadInputCase>& c) {
  forEach(c, kSequenceCommands, "sequence_empty",
          [](const Ws& w) {
            fs::create_directories(w.seq());
            fs::copy_file(w.fix / "bin/scans/sequence.json", w.seq() / "sequence.json");
          },
          2, {"scans", "holds no .pcd file", "lidarcal simulate"});
  forEach(c, kSequenceCommands, "sequence_missing",
          [](const Ws& w) { fs::create_directories(w.in); }, 2,
          {"scans", "does not exist", "check the path"});
  forEach(c, kSequenceCommands, "sequence_mixes_sensors",
          [](const Ws& w) {
            copySequence(w);
            // A 180-beam scan of another sensor in a sequence whose sequence.json says 360 beams.
            writeFile(w.in / "half.json", replaceAll(readFile(scenePath("paper_field.json")),
                                                     "\"beams\": 360", "\"beams\": 180"));
            ASSERT_EQ(runCli("simulate -q --scene " + (w.in / "half.json").string() + " --out " +
                             (w.in / "other").string() + " --stops 1 --scans-per-stop 1")
                          .exit_code,
                      0);
            fs::copy_file(w.in / "other/scans/scan_000000.pcd", w.seq() / "scan_000008.pcd");
          },
          2,
          {"scan_000008.pcd", "POINTS", "has 180 points", "beams = 360",
           "one sensor's scans per sequence"});
  forEach(c, kSequenceCommands, "sequence_upper_case_extension",
          [](const Ws& w) {
            copySequence(w);
            fs::copy_file(w.seq() / "scan_000003.pcd", w.seq() / "scan_000008.PCD");
          },
          2, {"scan_000008.PCD", "'.PCD'", "rename it"});
  forEach(c, kSequenceCommands, "sequence_same_scan_number_twice",
          [](const Ws& w) {
            copySequence(w);
            fs::copy_file(w.seq() / "scan_000003.pcd", w.seq() / "scan_3.pcd");
          },
          2, {"scans", "scan_3.pcd", "same scan number as scan_000003.pcd", "keep one"});
  forEach(c, kSequenceCommands, "sequence_numbers_not_zero_padded",
          [](const Ws& w) {
            copySequence(w);
            for (int i = 0; i < 8; ++i)
              fs::remove(w.seq() / ("scan_00000" + std::to_string(i) + ".pcd"));
            const fs::path src = w.fix / "bin/scans";
            fs::copy_file(src / "scan_000000.pcd", w.seq() / "s_2.pcd");
            fs::copy_file(src / "scan_000001.pcd", w.seq() / "s_10.pcd");
          },
          2, {"s_2.pcd", "sorts after s_10.pcd", "zero-padded"});
}

/// Data that cannot support a calibration (exit 3).
void unusableDataCases(std::vector<BadInputCase>& c) {
  const Commands calibrating = {{"calibrate", "calibrate {IN}/sim/scans --out {OUT}"},
                                {"run", "run {IN}/sim/scans --no-truth --out {OUT}"}};
  forEach(c, calibrating, "one_single_stop", simulated(scene(kPaperPoles, path(1, 3))), 3,
          {"sim/scans", "calibration", "too_few_stops", "has 1 stop ", "at least 3 stops",
           "its own VIEWPOINT", "made from one place", "--reference REF.json", "wall-to-wall spans",
           "lidarcal diagnose"});
  forEach(c, calibrating, "two_stops", simulated(scene(kPaperPoles, path(2, 3))), 3,
          {"sim/scans", "calibration", "too_few_stops", "has 2 stops", "at least 3 stops",
           "--reference REF.json", "lidarcal diagnose"});
  // Five stops, but a 2 m sensor sees each pole from two of them only.
  forEach(
      c, calibrating, "landmarks_at_fewer_than_3_stops",
      simulated(
          R"({"sensor": {"beams": 360, "range_min_m": 0.2, "range_max_m": 2.0, "bias_alpha": [0.0525, 0.8838, 0.0584],
              "noise": {"kind": "squared", "sigma_e": 0.0019176}},
            "path": {"start": {"x_m": -1.0}, "step_m": 1.2, "stops": 5, "scans_per_stop": 2},
            "landmarks": [{"x_m": -0.4, "y_m": 1.3, "radius_m": 0.12}, {"x_m": 2.0, "y_m": -1.3, "radius_m": 0.12},
                          {"x_m": 3.2, "y_m": 1.3, "radius_m": 0.12}]})"),
      3,
      {"sim/scans", "calibration", "no_usable_landmark", "3 or more stops", "zero landmarks",
       "lidarcal detect"});
  forEach(
      c, calibrating, "landmarks_on_the_path_line",
      simulated(scene(
          R"({"x_m": 4.2, "y_m": 0.0, "radius_m": 0.12}, {"x_m": 5.5, "y_m": 0.0, "radius_m": 0.12})",
          path(6, 2))),
      3,
      {"sim/scans", "calibration", "no_usable_landmark", "degenerate_geometry",
       "move it sideways"});
  forEach(
      c, calibrating, "circles_with_too_few_points",
      simulated(scene(
          R"({"x_m": 3.5, "y_m": 2.0, "radius_m": 0.02}, {"x_m": 3.0, "y_m": -2.5, "radius_m": 0.02},
                             {"x_m": 4.5, "y_m": 0.8, "radius_m": 0.02})",
          path(6, 2))),
      3, {"sim/scans", "calibration", "no_usable_landmark", "ERRORS.md"});
  // The dark-surface noise term on scans whose intensity field holds 0 everywhere (none recorded).
  const Commands dark = {
      {"calibrate", "calibrate {IN}/sim/scans --out {OUT} --effects dark_surface"}};
  forEach(c, dark, "dark_surface_without_intensity", simulated(scene(kPaperPoles, path(6, 2))), 3,
          {"sim/scans", "calibration", "no_intensity", "dark_surface", "intensities on"});
}

/// Model files (correct).
void modelFileCases(std::vector<BadInputCase>& c) {
  const Commands correcting = {{"correct", "correct {SEQ} --model {IN}/model.json --out {OUT}"}};
  forEach(c, correcting, "model_bias_not_monotone", withModel([](nlohmann::json& j) {
            j["bias"]["alpha"] = {0.0, 2.0, -0.3};
          }),
          3, {"model.json", "bias.alpha", "more than one distance", "lower --max-order"});
  forEach(c, correcting, "model_of_another_sensor_beams",
          withModel([](nlohmann::json& j) { j["sensor"]["beams"] = 720; }), 2,
          {"scan_000000.pcd", "POINTS", "has 360 beams", "model.json", "720",
           "calibrated on this sensor"});
  forEach(c, correcting, "model_of_another_sensor_range",
          withModel([](nlohmann::json& j) { j["sensor"]["range_max_m"] = 12.0; }), 2,
          {"model.json", "range_max_m", "range limits differ", "calibrate this one"});
  forEach(c, correcting, "model_not_json",
          [](const Ws& w) {
            copySequence(w);
            writeFile(w.in / "model.json",
                      "{\"format\": \"lidarcal-model/1\",\n \"bias\": [1, 2,\n");
          },
          2, {"model.json", "line 3", "not valid JSON"});
  forEach(c, correcting, "model_wrong_format",
          withModel([](nlohmann::json& j) { j["format"] = "something-else"; }), 2,
          {"model.json", "format", "lidarcal calibrate"});
  forEach(c, correcting, "model_bad_field",
          withModel([](nlohmann::json& j) { j["noise"]["kind"] = "pink"; }), 2,
          {"model.json", "noise.kind", "unknown noise kind"});
  forEach(c, correcting, "model_discrepancy_method", withModel([](nlohmann::json& j) {
            j["discrepancy"] = {{"method", "guess"}, {"sigma_m", 0.003}};
          }),
          2, {"model.json", "discrepancy.method", "\"none\" or \"reml\""});
  forEach(c, correcting, "model_discrepancy_negative", withModel([](nlohmann::json& j) {
            j["discrepancy"] = {{"method", "reml"}, {"sigma_m", -0.003}, {"dof", 5}};
          }),
          2, {"model.json", "discrepancy.sigma_m"});
  forEach(c, correcting, "model_unknown_status",
          withModel([](nlohmann::json& j) { j["diagnostics"]["status"] = "wobbly"; }), 2,
          {"model.json", "diagnostics.status", "'wobbly' is not a status lidarcal writes"});
  forEach(c, correcting, "model_failed_calibration",
          withModel([](nlohmann::json& j) { j["diagnostics"]["status"] = "joint_failed"; }), 3,
          {"model.json", "diagnostics.status", "not usable", "calibrate again"});
  forEach(c, correcting, "model_missing", [](const Ws& w) { copySequence(w); }, 2,
          {"model.json", "does not exist"});
}

/// Scene files (simulate).
void sceneFileCases(std::vector<BadInputCase>& c) {
  const Commands simulating = {{"simulate", "simulate --scene {IN}/scene.json --out {OUT}"}};
  forEach(c, simulating, "scene_not_json",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "scene.json", "{\"sensor\": {\"beams\": 360,}\n}");
          },
          2, {"scene.json", "line 1", "not valid JSON"});
  forEach(c, simulating, "scene_bad_field",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "scene.json",
                      R"({"sensor": {"range_min_m": 0.2, "range_max_m": "far"}, "path": {}})");
          },
          2, {"scene.json", "sensor.range_max_m", "must be a number", "FORMAT.md"});
  forEach(c, simulating, "scene_too_many_scans",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "scene.json",
                      scene(kPaperPoles, R"({"stops": 100000, "scans_per_stop": 1000})"));
          },
          2, {"scene.json", "path.stops", "10 million"});
}

/// Truth files (evaluate, detect --truth).
void truthFileCases(std::vector<BadInputCase>& c) {
  const auto simWithTruth = [](std::function<void(const fs::path&)> edit) {
    return [edit](const Ws& w) {
      copyTree(w.fix / "bin", w.in);
      edit(w.in);
    };
  };
  forEach(c,
          Commands{{"evaluate", "evaluate {SEQ} --truth {IN}/truth.json --out {OUT}"},
                   {"detect", "detect {SEQ} --truth {IN}/truth.json --out {OUT}"}},
          "truth_not_json",
          simWithTruth([](const fs::path& in) { writeFile(in / "truth.json", "[1, 2"); }), 2,
          {"truth.json", "not valid JSON"});
  forEach(c,
          Commands{{"evaluate", "evaluate {SEQ} --truth {IN}/truth.json --out {OUT}"},
                   {"detect", "detect {SEQ} --truth {IN}/truth.json --out {OUT}"}},
          "true_ranges_bad_value", simWithTruth([](const fs::path& in) {
            editFile(in / "true_ranges.csv", [](std::string& b) {
              const auto at = b.find('\n', b.find('\n') + 1) + 1;  // line 3
              b.insert(at, "0,1,abc,wall,1,0.1\n");
            });
          }),
          2, {"true_ranges.csv", "line 3", "true_range_m", "`abc`"});
}

/// Observation and odometry files (noise-consistency, docs/FORMAT.md "Noise estimation").
void noiseFileCases(std::vector<BadInputCase>& c) {
  const Commands estimating = {
      {"noise_consistency",
       "noise-consistency --observations {IN}/observations.csv --odometry {IN}/odometry.csv "
       "--method ml --out {OUT}"}};
  // A valid pair (4 stops, one sensor, two landmarks), then one file edited.
  const auto noiseFiles = [](std::string observations, std::string odometry) {
    return [observations, odometry](const Ws& w) {
      fs::create_directories(w.in);
      writeFile(w.in / "observations.csv", observations);
      writeFile(w.in / "odometry.csv", odometry);
    };
  };
  const std::string good_obs =
      "stop,sensor,landmark,range_m,bearing_rad\n0,0,1,2.0,0.5\n0,0,2,3.0,-0.5\n1,0,1,1.8,0.6\n1,0,"
      "2,2.9,-0.4\n"
      "2,0,1,1.6,0.7\n2,0,2,2.8,-0.3\n3,0,1,1.4,0.8\n3,0,2,2.7,-0.2\n";
  const std::string good_odo =
      "stop,dx_m,dy_m,dtheta_rad\n0,0,0,0\n1,0.3,0,0\n2,0.3,0,0\n3,0.3,0,0\n";
  forEach(c, estimating, "observations_bad_header",
          noiseFiles("stop,sensor,landmark,range,bearing\n0,0,1,2.0,0.5\n", good_odo), 2,
          {"observations.csv", "line 1", "header must be", "FORMAT.md"});
  forEach(c, estimating, "observations_not_a_number",
          noiseFiles("stop,sensor,landmark,range_m,bearing_rad\n0,0,1,2.0,0.5\n1,0,1,abc,0.5\n",
                     good_odo),
          2, {"observations.csv", "line 3", "range_m", "`abc`", "FORMAT.md"});
  forEach(
      c, estimating, "observations_sensor_id_too_large",
      noiseFiles("stop,sensor,landmark,range_m,bearing_rad\n0,4294967296,1,2.0,0.5\n", good_odo), 2,
      {"observations.csv", "line 2", "sensor", "too large"});
  forEach(c, estimating, "observations_infinite_range",
          noiseFiles("stop,sensor,landmark,range_m,bearing_rad\n0,0,1,inf,0.5\n", good_odo), 2,
          {"observations.csv", "line 2", "range_m", "not a finite number"});
  forEach(c, estimating, "observations_missing",
          [good_odo](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "odometry.csv", good_odo);
          },
          2, {"observations.csv", "does not exist"});
  forEach(c, estimating, "odometry_stops_out_of_order",
          noiseFiles(good_obs, "stop,dx_m,dy_m,dtheta_rad\n0,0,0,0\n2,0.3,0,0\n1,0.3,0,0\n"), 2,
          {"odometry.csv", "line 3", "stop", "in order"});
  forEach(c, estimating, "odometry_start_moves",
          noiseFiles(good_obs, "stop,dx_m,dy_m,dtheta_rad\n0,1,0,0\n1,0.3,0,0\n"), 2,
          {"odometry.csv", "line 2", "stop 0 is the start"});
  forEach(c, estimating, "odometry_no_stop", noiseFiles(good_obs, "stop,dx_m,dy_m,dtheta_rad\n"), 2,
          {"odometry.csv", "holds no stop"});
}

/// Odometry tuples (lidarcal odometry, docs/FORMAT.md "Odometry tuples").
void odometryTupleCases(std::vector<BadInputCase>& c) {
  const Commands odometry = {{"odometry", "odometry {IN}/drive.tuple --out {OUT}"}};
  const auto tuples = [](std::string text) {
    return [text](const Ws& w) {
      fs::create_directories(w.in);
      writeFile(w.in / "drive.tuple", text);
    };
  };
  const std::string tuple = R"({"T": 0.8, "phi_l": 0.5, "phi_r": -0.5, "sm": [0.001, 0, -0.18]})";
  /// `n` tuples of driving straight at one speed: the wheel radii cannot be told apart.
  const auto straight = [](int n) {
    std::string text;
    for (int k = 0; k < n; ++k)
      text += R"({"T": 0.8, "phi_l": 0.5, "phi_r": 0.5, "sm": [0.0082, )" +
              std::to_string(1e-4 * (k % 3)) + ", 0]}\n";
    return text;
  };
  /// Straight driving and turns in place, the turns' sign that of swapped wheels.
  const auto swapped = [] {
    std::string text;
    for (int k = 0; k < 200; ++k)
      text += k % 2 ? R"({"T": 0.8, "phi_l": 0.5, "phi_r": 0.5, "sm": [0.0082, 0, 0]})"
                      "\n"
                    : R"({"T": 0.8, "phi_l": -0.5, "phi_r": 0.5, "sm": [0.0005, )" +
                          std::to_string(1e-4 * (k % 3)) + ", -0.18]}\n";
    return text;
  };
  forEach(c, odometry, "tuples_cut_short", tuples(tuple + "\n" + tuple.substr(0, 25)), 2,
          {"drive.tuple", "object 2 (line 2)", "cut short"});
  forEach(c, odometry, "tuples_missing_field",
          tuples(tuple + R"({"T": 0.8, "phi_l": 0.5, "sm": [0, 0, 0]})"), 2,
          {"drive.tuple", "object 2 (line 1), field phi_r", "is missing", "FORMAT.md"});
  forEach(c, odometry, "tuples_not_a_number",
          tuples(R"({"T": 0.8, "phi_l": "fast", "phi_r": 0, "sm": [0, 0, 0]})"), 2,
          {"drive.tuple", "object 1 (line 1), field phi_l", "must be a number"});
  forEach(c, odometry, "tuples_interval_not_positive",
          tuples(R"({"T": 0, "phi_l": 0.5, "phi_r": 0, "sm": [0, 0, 0]})"), 2,
          {"drive.tuple", "field T", "must be positive"});
  forEach(c, odometry, "tuples_empty", tuples("\n"), 2, {"drive.tuple", "holds no tuple"});
  forEach(c, odometry, "tuples_only_straight", tuples(straight(200)), 3,
          {"drive.tuple", "calibration", "degenerate_motion", "turns in both directions"});
  forEach(c, odometry, "tuples_too_few", tuples(straight(5)), 3,
          {"drive.tuple", "too_few_samples", "record longer"});
  forEach(c, odometry, "tuples_wheels_swapped", tuples(swapped()), 3,
          {"drive.tuple", "negative_axle", "phi_l must be the left wheel"});
}

/// Importing a ROS bag by a topic it does not hold (needs the shared data and ROS1 bag support).
BadInputCase rosbagWithoutTheTopic() {
  BadInputCase k;
  k.name = "rosbag_without_the_topic_import";
  k.args = "import --from rosbag1 {SHARED}/rplidar_a2_room/rplidar_1.bag --topic /scan --out {OUT}";
  k.prepare = [](const Ws& w) { fs::create_directories(w.in); };
  k.message = {"rplidar_1.bag", "--topic /scan", "no such topic", "/scan_rplidar"};
  k.skip = [](const Ws&) -> std::string {
    if (!fs::exists(sharedData() / "rplidar_a2_room/rplidar_1.bag")) return "shared data absent";
    const auto r =
        runCli("import --from rosbag1 " +
               (sharedData() / "rplidar_a2_room/rplidar_1.bag").string() + " --list-topics");
    return r.exit_code == 0 ? "" : "built without ROS1 bag support";
  };
  k.also_unchanged = [](const Ws&) {
    return std::vector<fs::path>{sharedData() / "rplidar_a2_room"};
  };
  return k;
}

/// The importers.
void importerCases(std::vector<BadInputCase>& c) {
  const auto importing = [](const char* from, const char* file) {
    return Commands{
        {"import", std::string("import --from ") + from + " {IN}/" + file + " --out {OUT}"}};
  };
  forEach(c, importing("carmen", "cut.log.gz"), "carmen_gzip_cut_short",
          [](const Ws& w) {
            fs::create_directories(w.in);
            std::string log;
            for (int k = 0; k < 2000; ++k) log += flaserLine(181, 1.0 + 0.001 * k);
            writeGzip(w.in / "full.log.gz", log);
            const std::string gz = readFile(w.in / "full.log.gz");
            fs::remove(w.in / "full.log.gz");
            writeFile(w.in / "cut.log.gz", gz.substr(0, gz.size() * 2 / 3));
          },
          2, {"cut.log.gz", "after line", "gzip data is damaged or cut short", "gzip -t"});
  forEach(c, importing("carmen", "bad.log"), "carmen_line_cut_short",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "bad.log",
                      flaserLine(181, 2.0) + "FLASER 181 1 2 3 0 0 0 0 0 0 1.5 host 1.5\n");
          },
          2, {"bad.log", "line 2 (FLASER)", "expected 191", "fix or delete the line"});
  forEach(c, importing("carmen", "odom.log"), "carmen_no_laser_line",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "odom.log", "ODOM 0 0 0 0 0 0 1.5 host 1.5\n");
          },
          2, {"odom.log", "not a CARMEN laser log", "check --from"});
  forEach(c, importing("ydlidar", "x4.dat"), "ydlidar_bad_number",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "x4.dat", "0,0,0.1,1.0,1.1,1.2\n5,1,0.1,1.0,x,1.2\n");
          },
          2, {"x4.dat", "line 2", "range 1 is 'x'"});
  forEach(c, importing("csv", "a.csv"), "csv_missing_column",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "a.csv", "scan,x_m,y_m,angle_rad,range_m\n0,0,0,0,1\n");
          },
          2, {"a.csv", "line 1 (header)", "no column 'yaw_rad'"});
  forEach(c, importing("csv", "a.csv"), "csv_pose_changes_within_a_scan",
          [](const Ws& w) {
            fs::create_directories(w.in);
            writeFile(w.in / "a.csv",
                      "scan,x_m,y_m,yaw_rad,angle_rad,range_m\n0,0,0,0,0,1\n0,1,0,0,0.1,1\n");
          },
          2, {"a.csv", "line 3", "a scan has one sensor pose"});
  forEach(c, importing("csv", "none.csv"), "import_input_missing",
          [](const Ws& w) { fs::create_directories(w.in); }, 2, {"none.csv", "does not exist"});
  c.push_back(rosbagWithoutTheTopic());
}

/// Where the output goes, for every command that writes.
void outputCases(std::vector<BadInputCase>& c) {
  forEach(c, kWritingCommands, "out_is_the_input", [](const Ws& w) { writableInputs(w); }, 2,
          {"--out", "inside it", "outside the input"});
  for (auto& k : c)
    if (k.name.rfind("out_is_the_input_", 0) == 0) {
      const std::string& name = k.name;
      const std::string input = name.find("simulate") != std::string::npos ? "{IN}/scene.json"
                                : name.find("import") != std::string::npos ? "{IN}/scans.csv"
                                                                           : "{SEQ}";
      k.args = replaceAll(k.args, "--out {OUT}", "--out " + input);
      // simulate reads a file, not a directory: its output may not be the scene file either.
    }
  // (simulate and import read a file: "inside" does not apply; out_is_the_input covers them.)
  forEach(c, Commands(kWritingCommands.begin(), kWritingCommands.begin() + 4),
          "out_inside_the_input", [](const Ws& w) { writableInputs(w); }, 2,
          {"--out", "inside it", "outside the input"});
  for (auto& k : c)
    if (k.name.rfind("out_inside_the_input_", 0) == 0)
      k.args = replaceAll(k.args, "--out {OUT}", "--out {SEQ}/out");
  forEach(c, kWritingCommands, "out_parent_is_a_file", [](const Ws& w) { writableInputs(w); }, 2,
          {"--out", "not a directory"});
  for (auto& k : c)
    if (k.name.rfind("out_parent_is_a_file_", 0) == 0)
      k.args = replaceAll(k.args, "--out {OUT}", "--out {IN}/file.txt/result");
  forEach(c, kWritingCommands, "out_in_proc", [](const Ws& w) { writableInputs(w); }, 2,
          {"/proc/result", "writable"});
  for (auto& k : c)
    if (k.name.rfind("out_in_proc_", 0) == 0)
      k.args = replaceAll(k.args, "--out {OUT}", "--out /proc/result");
  forEach(c, kWritingCommands, "out_directory_not_writable", [](const Ws& w) { writableInputs(w); },
          2, {"result", "check that", "writable"});
  for (auto& k : c)
    if (k.name.rfind("out_directory_not_writable_", 0) == 0) {
      k.shell_prefix = "chmod 0555 {OUTDIR}";
      k.skip = [](const Ws& w) -> std::string {
        return permissionsAreIgnored(w.in) ? "running as root: a read-only mode does not stop "
                                             "writes (the /proc case covers it)"
                                           : "";
      };
    }
  // Disk full, simulated without privileges: a file-size limit (ulimit -f, in KiB) with SIGXFSZ
  // ignored makes write() fail with EFBIG as a full disk fails with ENOSPC.
  forEach(c, kWritingCommands, "disk_full", [](const Ws& w) { writableInputs(w); }, 2,
          // the final path, not the staging one
          {"outdir/result", "disk full?", "free some space"});
  for (auto& k : c)
    if (k.name.rfind("disk_full_", 0) == 0) {
      // 1 KiB: model.json (~10 KB) and scans (~4.4 KB) cannot be written; small files can.
      k.shell_prefix = "trap '' XFSZ; ulimit -f 1";
    }
  forEach(c,
          Commands{{"calibrate", "calibrate {SEQ} --out {IN}"},
                   {"evaluate", "evaluate {SEQ} --truth {IN}/truth.json --out {IN}"}},
          "out_file_is_a_directory", [](const Ws& w) { copyTree(w.fix / "bin", w.in); }, 2,
          {"is a directory"});
  forEach(c, Commands{{"detect", "detect {SEQ} --out {IN}/truth.json"}}, "out_directory_is_a_file",
          [](const Ws& w) { copyTree(w.fix / "bin", w.in); }, 2,
          {"truth.json", "--out", "is a file"});
}

std::vector<BadInputCase> cases() {
  std::vector<BadInputCase> c;
  scanFileCases(c);
  sequenceDirectoryCases(c);
  unusableDataCases(c);
  modelFileCases(c);
  sceneFileCases(c);
  truthFileCases(c);
  noiseFileCases(c);
  odometryTupleCases(c);
  importerCases(c);
  outputCases(c);
  return c;
}

class BadInput : public ::testing::TestWithParam<BadInputCase> {};

TEST_P(BadInput, FailsCleanlyNamingFileItemAndRemedy) {
  const BadInputCase& k = GetParam();
  TempDir dir;
  Ws w{dir / "in", dir / "outdir/result", fixtures()};
  fs::create_directories(w.out.parent_path());
  ASSERT_NO_FATAL_FAILURE(k.prepare(w));
  if (k.skip)
    if (const std::string why = k.skip(w); !why.empty()) GTEST_SKIP() << why;
  std::string args = replaceAll(k.args, "{SEQ}", w.seq().string());
  args = replaceAll(args, "{IN}", w.in.string());
  args = replaceAll(args, "{OUT}", w.out.string());
  args = replaceAll(args, "{FIX}", w.fix.string());
  args = replaceAll(args, "{SHARED}", sharedData().string());
  const std::string prefix = replaceAll(k.shell_prefix, "{OUTDIR}", w.out.parent_path().string());
  std::vector<fs::path> unchanged = {w.in};
  if (k.also_unchanged)
    for (const auto& p : k.also_unchanged(w)) unchanged.push_back(p);
  std::vector<std::map<std::string, std::string>> before;
  for (const auto& p : unchanged) before.push_back(snapshot(p));
  const auto listing_before = listing(w.in);

  const CliResult r = runCliPrefixed(prefix, args);
  if (!prefix.empty()) ::chmod(w.out.parent_path().c_str(), 0755);
  SCOPED_TRACE("lidarcal " + args + "\nstderr: " + r.err);
  // LIDARCAL_PRINT_MESSAGES=1 prints every message (to keep docs/ERRORS.md in step).
  if (std::getenv("LIDARCAL_PRINT_MESSAGES"))
    std::printf("MESSAGE %s: %s", k.name.c_str(), r.err.c_str());

  EXPECT_EQ(r.exit_code, k.exit_code);
  EXPECT_NE(r.err.find(k.exit_code == 3 ? "lidarcal: cannot proceed: " : "lidarcal: error: "),
            std::string::npos);
  for (const auto& part : k.message)
    EXPECT_NE(r.err.find(part), std::string::npos) << "missing: " << part;
  // The remedy closes the message in parentheses.
  std::string last = r.err.substr(0, r.err.find_last_not_of('\n') + 1);
  last = last.substr(last.rfind('\n') == std::string::npos ? 0 : last.rfind('\n') + 1);
  EXPECT_TRUE(!last.empty() && last.back() == ')' && last.find(" (") != std::string::npos)
      << "no remedy: " << last;
  EXPECT_EQ(r.out.find("internal error"), std::string::npos);
  // Input unchanged, byte for byte and entry for entry.
  for (std::size_t i = 0; i < unchanged.size(); ++i)
    EXPECT_TRUE(snapshot(unchanged[i]) == before[i]) << unchanged[i];
  EXPECT_EQ(listing(w.in), listing_before);
  // Nothing written: the output directory's parent is as it was (empty), no staging leftovers.
  EXPECT_TRUE(listing(w.out.parent_path()).empty()) << "left behind in " << w.out.parent_path();
  for (const auto& name : listing(dir.path()))
    EXPECT_TRUE(
        name.find(".partial-") == std::string::npos && name.find(".tmp-") == std::string::npos &&
        name.find(".old-") == std::string::npos && name.find(".probe-") == std::string::npos)
        << "left behind: " << name;
}

INSTANTIATE_TEST_SUITE_P(Catalogue, BadInput, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<BadInputCase>& p) {
                           return p.param.name;
                         });

}  // namespace
}  // namespace lidarcal
