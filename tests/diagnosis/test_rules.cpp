// SPDX-License-Identifier: BSD-3-Clause
// The verdict's rules (diagnosis/rules.hpp): nameCause on hand-made candidates, and the rule
// table as docs/DIAGNOSIS.md documents it, in the same order.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "calibration/joint_refinement.hpp"
#include "common/rng.hpp"
#include "diagnosis/diagnose_cases.hpp"
#include "diagnosis/rules.hpp"
#include "test_util.hpp"

namespace lidarcal::diagnosis {
using namespace lidarcal::calibration;  // the joint refinement the diagnosis refits with
namespace {

TEST(DiagnoseStats, CauseNamingRules) {
  auto cand = [](Effect e, double p, double gain, double se, int k, bool id = true) {
    CandidateResult c;
    c.effect = e;
    c.p_value = p;
    c.heldout_gain_nats_per_point = gain;
    c.heldout_gain_se = se;
    c.parameters = k;
    c.identifiable = id;
    return c;
  };
  const Effect a = Effect::incidence_noise, b = Effect::incidence_bias, c = Effect::range_drift,
               d = Effect::mixed_pixels;
  const Effect per_stop = Effect::heading_error, common = Effect::angle_offset;
  std::string why;
  std::vector<CandidateResult> none = {cand(a, 0.2, 0.001, 0.001, 1),
                                       cand(b, 0.5, -0.01, 0.001, 1)};
  EXPECT_EQ(nameCause(none, 0.01, why), cause::kNone);
  // Largest significant gain wins.
  std::vector<CandidateResult> two = {cand(a, 1e-9, 0.01, 0.001, 1),
                                      cand(b, 1e-12, 0.05, 0.001, 1)};
  EXPECT_EQ(nameCause(two, 0.01, why), toString(b));
  // A simpler effect nested in the top one, within two standard errors, is preferred (parsimony);
  // one that is not nested is not.
  std::vector<CandidateResult> nested = {cand(per_stop, 1e-12, 0.0105, 0.001, 10),
                                         cand(common, 1e-12, 0.0100, 0.001, 1)};
  EXPECT_EQ(nameCause(nested, 0.01, why, {{common, per_stop}}), toString(common));
  EXPECT_EQ(nameCause(nested, 0.01, why), toString(per_stop));
  // A significant effect that cannot be estimated apart from the baseline.
  std::vector<CandidateResult> confounded = {cand(a, 1e-12, 0.05, 0.001, 1, false),
                                             cand(b, 1e-9, 0.01, 0.001, 1)};
  EXPECT_EQ(nameCause(confounded, 0.01, why), cause::kNotIdentifiable);
  // Two effects that explain the data alike and are declared indistinguishable.
  std::vector<CandidateResult> twins = {cand(a, 1e-12, 0.0500, 0.002, 1),
                                        cand(b, 1e-12, 0.0495, 0.002, 1)};
  EXPECT_EQ(nameCause(twins, 0.01, why, {}, {{a, b}}), cause::kNotIdentifiable);
  // Holm: p = 0.004 is not significant among four candidates at alpha 0.01.
  std::vector<CandidateResult> holm = {cand(a, 0.004, 0.01, 0.001, 1), cand(b, 0.9, 0, 1, 1),
                                       cand(c, 0.9, 0, 1, 1), cand(d, 0.9, 0, 1, 1)};
  EXPECT_EQ(nameCause(holm, 0.01, why), cause::kNone);
}

TEST(DiagnoseRules, TheTableIsTheDocumentedOneInItsOrder) {
  // docs/DIAGNOSIS.md lists the rules as rows "| `id` | ...", in the order the code applies them.
  std::ifstream in(test::sourceDir() / "docs/DIAGNOSIS.md");
  ASSERT_TRUE(in) << "docs/DIAGNOSIS.md";
  std::vector<std::string> documented;
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("| `", 0) == 0) documented.push_back(line.substr(3, line.find('`', 3) - 3));
  std::vector<std::string> coded;
  for (const VerdictRule& rule : verdictRules()) {
    coded.push_back(rule.id);
    EXPECT_TRUE(std::string(rule.condition).size() > 0 && std::string(rule.reason).size() > 0)
        << rule.id;
  }
  EXPECT_EQ(documented, coded);
}

}  // namespace
}  // namespace lidarcal::diagnosis
