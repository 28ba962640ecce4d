// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The bad-input catalogue's input builders (test_bad_input.cpp, test_input_warnings.cpp): the
// shared fixtures, copies of good inputs with one edit, simulated scenes.

#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bad_input_util.hpp"

namespace lidarcal::test {

inline std::string scenePath(const char* name) {
  return (sourceDir() / "data/scenes" / name).string();
}

/// Shared fixtures, built once: FIX/bin (binary, 4 stops x 2 scans: enough to calibrate, so that
/// output failures are reached), FIX/ascii (the same in ASCII), FIX/model.json (calibrated on
/// 10 stops x 2 scans of the paper's field).
inline const fs::path& fixtures() {
  static const fs::path dir = cachedFixture("bad-input", [](const fs::path& d) {
    const std::string scene = scenePath("paper_field.json");
    for (const auto& [name, flags] :
         {std::pair<const char*, const char*>{"bin", ""}, {"ascii", " --ascii"}}) {
      const auto r = runCli("simulate -q --scene " + scene + " --out " + (d / name).string() +
                            " --stops 4 --scans-per-stop 2 --seed 3" + flags);
      EXPECT_EQ(r.exit_code, 0) << r.err;
    }
    auto r = runCli("simulate -q --scene " + scene + " --out " + (d / "cal").string() +
                    " --scans-per-stop 2 --seed 4");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    r = runCli("calibrate -q " + (d / "cal/scans").string() + " --out " +
               (d / "model.json").string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
  });
  return dir;
}

inline void copySequence(const Ws& w) { copyTree(w.fix / "bin/scans", w.seq()); }
inline void copyAsciiSequence(const Ws& w) { copyTree(w.fix / "ascii/scans", w.seq()); }

/// Copies the binary sequence and edits one scan.
inline std::function<void(const Ws&)> withScan(const char* file,
                                               std::function<void(std::string&)> edit) {
  return [file, edit](const Ws& w) {
    copySequence(w);
    editFile(w.seq() / file, edit);
  };
}

/// Copies the good model and edits its JSON.
inline std::function<void(const Ws&)> withModel(std::function<void(nlohmann::json&)> edit) {
  return [edit](const Ws& w) {
    copySequence(w);
    auto j = nlohmann::json::parse(readFile(w.fix / "model.json"));
    edit(j);
    writeFile(w.in / "model.json", j.dump(2));
  };
}

/// Writes a scene (JSON text) and simulates it into IN/sim.
inline std::function<void(const Ws&)> simulated(std::string scene_json, std::string flags = "") {
  return [scene_json, flags](const Ws& w) {
    fs::create_directories(w.in);
    writeFile(w.in / "scene.json", scene_json);
    const auto r = runCli("simulate -q --scene " + (w.in / "scene.json").string() + " --out " +
                          (w.in / "sim").string() + " " + flags);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  };
}

/// The paper's sensor and walls with the given landmarks and path.
inline std::string scene(const std::string& landmarks, const std::string& path,
                         const std::string& sensor_extra = "") {
  return R"({"sensor": {"beams": 360, "range_min_m": 0.2, "range_max_m": 6.0, "bias_alpha": [0.0525, 0.8838, 0.0584],
      "noise": {"kind": "squared", "sigma_e": 0.0019176})" +
         sensor_extra + R"(},
    "path": )" +
         path + R"(, "landmarks": [)" + landmarks + R"(],
    "walls": [{"x0_m": -1.5, "y0_m": -3.8, "x1_m": 5.0, "y1_m": -3.8}, {"x0_m": 5.0, "y0_m": -3.8, "x1_m": 5.0, "y1_m": 4.5},
              {"x0_m": 5.0, "y0_m": 4.5, "x1_m": -1.5, "y1_m": 4.5}, {"x0_m": -1.5, "y0_m": 4.5, "x1_m": -1.5, "y1_m": -3.8}]})";
}
inline const char* kPaperPoles =
    R"({"x_m": 1.5, "y_m": 0.75, "radius_m": 0.12}, {"x_m": 0.3, "y_m": 2.2, "radius_m": 0.12},
    {"x_m": 2.4, "y_m": 3.4, "radius_m": 0.12}, {"x_m": 3.9, "y_m": -1.3, "radius_m": 0.12}, {"x_m": 0.9, "y_m": -2.8, "radius_m": 0.12})";
inline std::string path(int stops, int scans = 2) {
  return R"({"step_m": 0.3, "sigma_s_m": 0.02, "sigma_psi_deg": 0.5, "stops": )" +
         std::to_string(stops) + R"(, "scans_per_stop": )" + std::to_string(scans) + "}";
}

inline std::string flaserLine(int n, double r) {
  std::string s = "FLASER " + std::to_string(n);
  for (int i = 0; i < n; ++i) s += " " + std::to_string(r);
  return s + " 0 0 0 0 0 0 1.5 host 1.5\n";
}

}  // namespace lidarcal::test
