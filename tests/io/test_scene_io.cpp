// SPDX-License-Identifier: BSD-3-Clause
// Scene and truth files.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "common/effect.hpp"
#include "common/errors.hpp"
#include "common/range_effects.hpp"
#include "io/scene_io.hpp"
#include "test_util.hpp"

namespace lidarcal::io {
namespace {

using test::TempDir;

TEST(SceneIo, ReadsTheBundledPaperFieldScene) {
  const Scene s = readScene(test::sourceDir() / "data/scenes/paper_field.json");
  EXPECT_EQ(s.landmarks.size(), 5u);
  for (const auto& l : s.landmarks) EXPECT_DOUBLE_EQ(l.radius_m, 0.12);
  EXPECT_EQ(s.path.stops, 10);
  EXPECT_DOUBLE_EQ(s.path.step_m, 0.30);
  EXPECT_EQ(s.sensor.beams, 360);
  EXPECT_NEAR(s.sensor.angle_increment_rad, deg2rad(1.0), 1e-15);
  EXPECT_EQ(s.sensor.range.bias.alpha, (std::vector<double>{0.0525, 0.8838, 0.0584}));
  EXPECT_DOUBLE_EQ(s.sensor.range.range_min_m, 0.2);
  EXPECT_DOUBLE_EQ(s.sensor.range.range_max_m, 6.0);
}

struct BadScene {
  const char* json;
  const char* item;
};

class BadSceneTest : public ::testing::TestWithParam<BadScene> {};

TEST_P(BadSceneTest, NamesTheField) {
  TempDir dir;
  test::writeFile(dir / "s.json", GetParam().json);
  try {
    readScene(dir / "s.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir / "s.json").string());
    EXPECT_EQ(e.item(), GetParam().item) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadSceneTest,
    ::testing::Values(
        BadScene{"[1, 2]", "(top level)"}, BadScene{R"({"path": {}})", "sensor"},
        BadScene{R"({"sensor": {"range_min_m": 0.2}, "path": {}})", "sensor.range_max_m"},
        BadScene{R"({"sensor": {"range_min_m": 1, "range_max_m": 0.5}, "path": {}})",
                 "sensor.range_min_m"},
        BadScene{
            R"({"sensor": {"range_min_m": 0, "range_max_m": 5, "bias_alpha": [1, "x"]}, "path": {}})",
            "sensor.bias_alpha[1]"},
        BadScene{
            R"({"sensor": {"range_min_m": 0, "range_max_m": 5, "noise": {"kind": "pink"}}, "path": {}})",
            "sensor.noise.kind"},
        BadScene{R"({"sensor": {"range_min_m": 0, "range_max_m": 5}, "path": {"stops": 0}})",
                 "path.stops"},
        BadScene{R"({"sensor": {"range_min_m": 0, "range_max_m": 5}, "path": {},
                                   "landmarks": [{"x_m": 1, "y_m": 1, "radius_m": 0.1}, {"x_m": 1, "y_m": 1, "radius_m": -0.1}]})",
                 "landmarks[1].radius_m"},
        BadScene{"{\n\"sensor\": {,}\n}", "line 2 column 12"}));

// The effect table's scene keys (common/effect.hpp) are the keys the scene reader reads: every
// "sensor.effects.*" key of the table, set in a scene, comes back from reading and writing it.
TEST(SceneIo, EveryEffectSceneKeyOfTheTableIsRead) {
  TempDir dir;
  nlohmann::json base;
  std::ifstream(test::sourceDir() / "data/scenes/paper_field.json") >> base;
  int keys = 0;
  for (const auto& i : effectTable()) {
    const std::string key = i.scene_key;
    const std::string prefix = "sensor.effects.";
    if (key.rfind(prefix, 0) != 0) continue;
    ++keys;
    const std::string field = key.substr(prefix.size());
    nlohmann::json j = base;
    j["sensor"]["effects"] = {{field, i.effect == Effect::mixed_pixels ? 0.5 : 3.0}};
    test::writeFile(dir / "s.json", j.dump());
    const auto back = sceneToJson(readScene(dir / "s.json"));
    EXPECT_TRUE(back["sensor"]["effects"].contains(field)) << i.name << ": " << key;
  }
  EXPECT_EQ(keys, 7);
}

/// Writes `scene` to `file` and expects readScene to refuse it with an InputError naming `key`.
void expectRefusedNaming(const std::filesystem::path& file, const nlohmann::json& scene,
                         const std::string& key) {
  test::writeFile(file, scene.dump());
  try {
    readScene(file);
    ADD_FAILURE() << "accepted a scene with a bad " << key;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}

TEST(SceneIo, SurfaceIntensitiesAndTheDarkNoiseRoundTrip) {
  TempDir dir;
  nlohmann::json j;
  std::ifstream(test::sourceDir() / "data/scenes/paper_field.json") >> j;
  j["landmarks"][1]["intensity"] = 35.5;
  j["sensor"]["effects"] = {{"dark_noise_exponent", 0.5}, {"dark_reference_intensity", 90.0}};
  test::writeFile(dir / "s.json", j.dump());
  const Scene s = readScene(dir / "s.json");
  EXPECT_EQ(s.landmarks[0].intensity, 0.0);  // none recorded
  EXPECT_EQ(s.landmarks[1].intensity, 35.5);
  EXPECT_EQ(s.sensor.effects.dark_noise_exponent, 0.5);
  EXPECT_EQ(s.sensor.effects.dark_reference_intensity, 90.0);
  const auto back = sceneToJson(s);
  // scenes without intensities keep their bytes
  EXPECT_FALSE(back["landmarks"][0].contains("intensity"));
  EXPECT_EQ(back["landmarks"][1]["intensity"], 35.5);
  EXPECT_EQ(back["sensor"]["effects"]["dark_reference_intensity"], 90.0);
  // A reference of 0 makes no sense (the factor is (I_ref / I)^delta): refused, naming the key.
  j["sensor"]["effects"]["dark_reference_intensity"] = 0.0;
  expectRefusedNaming(dir / "s.json", j, "dark_reference_intensity");
}

TEST(SceneIo, TheRippleOfTheBiasRoundTripsAndItsWavelengthMustBePositive) {
  TempDir dir;
  nlohmann::json j;
  std::ifstream(test::sourceDir() / "data/scenes/paper_field.json") >> j;
  j["sensor"]["effects"] = {
      {"ripple_amplitude_m", 0.004}, {"ripple_wavelength_m", 0.3}, {"ripple_phase_rad", 1.0}};
  test::writeFile(dir / "s.json", j.dump());
  const Scene s = readScene(dir / "s.json");
  EXPECT_EQ(s.sensor.effects.ripple_amplitude_m, 0.004);
  EXPECT_EQ(s.sensor.effects.ripple_wavelength_m, 0.3);
  EXPECT_EQ(s.sensor.effects.ripple_phase_rad, 1.0);
  EXPECT_TRUE(s.sensor.effects.any());
  // The sensor's mean reading gains A sin(2 pi d / lambda + phi).
  EXPECT_NEAR(rangeRipple(s.sensor.effects, 0.075),
              0.004 * std::sin(0.5 * 3.14159265358979323846 + 1.0), 1e-15);
  const auto back = sceneToJson(s);
  EXPECT_EQ(back["sensor"]["effects"]["ripple_wavelength_m"], 0.3);
  j["sensor"]["effects"]["ripple_wavelength_m"] = 0.0;
  expectRefusedNaming(dir / "s.json", j, "ripple_wavelength_m");
}

TEST(SceneIo, MissingSceneFileIsReported) {
  try {
    readScene("/nonexistent/scene.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

TEST(SceneIo, TruthRoundTrip) {
  TempDir dir;
  Truth t;
  t.seed = 18446744073709551557ULL;
  t.scene = readScene(test::sourceDir() / "data/scenes/paper_field.json");
  t.stops.push_back(TruthStop{{0, 0, 0}, {0.01, -0.02, 0.003}, 0, 10});
  t.stops.push_back(TruthStop{{0.3, 0, 0}, {0.31, 0.02, -0.001}, 10, 10});
  writeTruth(dir / "truth.json", t);
  const Truth r = readTruth(dir / "truth.json");
  EXPECT_EQ(r.seed, t.seed);
  ASSERT_EQ(r.stops.size(), 2u);
  EXPECT_DOUBLE_EQ(r.stops[1].actual.x_m, 0.31);
  EXPECT_DOUBLE_EQ(r.stops[1].actual.yaw_rad, -0.001);
  EXPECT_EQ(r.stops[1].first_scan, 10u);
  EXPECT_EQ(r.scene.landmarks.size(), 5u);
  EXPECT_EQ(r.scene.sensor.range.bias.alpha, t.scene.sensor.range.bias.alpha);
  EXPECT_NEAR(r.scene.sensor.range.noise.sigma_e, t.scene.sensor.range.noise.sigma_e, 1e-15);
}

}  // namespace
}  // namespace lidarcal::io
