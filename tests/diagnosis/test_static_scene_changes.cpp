// SPDX-License-Identifier: BSD-3-Clause
// Whether a recording from one pose stayed one pose (diagnosis/static_scene/scene_changes.hpp):
// beams that saw an object carried away are left out, scattered outliers are not a scene change.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnose_test_util.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/static_scene.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

using test::staticRoom;
NoiseModel squared(double sigma_e) { return test::squaredNoise(sigma_e); }

/// The beams of a 20-degree sector (sensor frame, 10 to 29 degrees) of the room at 0.6 of their
/// range in the scans `moved` says: an object standing in front of the walls there.
diagnosis::StaticScans roomWithObject(std::uint64_t seed,
                                      const std::function<bool(std::uint32_t)>& moved) {
  diagnosis::StaticScans s = staticRoom({}, squared(0.0015), seed);
  for (auto& r : s.readings)
    if (r.angle_rad > deg2rad(9.5) && r.angle_rad < deg2rad(29.5) && moved(r.scan))
      r.range_m *= 0.6;
  return s;
}

constexpr double kSectorBeams = 20.0;  // the 1-degree beams from 10 to 29 degrees

TEST(DiagnoseStatic, BeamsThatSawAnObjectCarriedAwayAreLeftOutAndTheRoomStaysClean) {
  // A box stood in front of the walls for the first third of the recording, then was carried
  // away (the forklift recordings: reflectors and people move while the sensor stands still).
  // The sensor did not move: no windows; the sector's beams are left out, and the rest of the
  // room is the clean room it is.
  DiagnoseConfig dc;
  dc.replicas = 9;
  const auto r =
      diagnoseStatic(roomWithObject(3, [](std::uint32_t scan) { return scan < 50; }), dc);
  ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
  EXPECT_EQ(r.baseline_extra.at("window_scans"), 0.0);
  // Every beam of the sector; a few beams' readings fall in two bins (their angles, computed
  // from float coordinates, round apart), hence the margin of six.
  EXPECT_GE(r.baseline_extra.at("scene_changed_bins"), kSectorBeams);
  EXPECT_LE(r.baseline_extra.at("scene_changed_bins"), kSectorBeams + 6.0);
  EXPECT_EQ(r.primary_cause, cause::kNone) << r.decision;
  EXPECT_NEAR(r.baseline.noise.sigma_e, 0.0015, 0.0002);
}

TEST(DiagnoseStatic, ReadingsOffTheirBeamAtRandomScansAreNotASceneChange) {
  // The same sector's beams at 0.6 of their range in a third of the scans drawn at random (the
  // test's own stream): off readings scattered in time are the sensor's (mixed pixels, tails),
  // not an object carried in or out, and stay in the data.
  for (std::uint64_t seed : {11u, 12u}) {
    SCOPED_TRACE(seed);
    auto rng = makeRng(seed, 5);
    std::vector<bool> off(150);
    for (std::size_t t = 0; t < off.size(); ++t)
      off[t] = std::uniform_real_distribution<double>(0.0, 1.0)(rng) < 1.0 / 3.0;
    DiagnoseConfig dc;
    dc.replicas = 5;
    dc.candidates = {Effect::mixed_pixels};
    const auto r =
        diagnoseStatic(roomWithObject(3, [&](std::uint32_t scan) { return off[scan]; }), dc);
    ASSERT_STREQ(r.status.name(), "ok") << r.status.message;
    EXPECT_EQ(r.baseline_extra.at("scene_changed_bins"), 0.0);
  }
}

}  // namespace
}  // namespace lidarcal::diagnosis
