// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Many tests at once: p-values adjusted so the chance of any false rejection in the family stays
// at the level set.

#include <vector>

namespace lidarcal {

/// Holm's step-down adjustment of p-values (NaN entries are left out and stay NaN): the k-th
/// smallest of m is multiplied by m - k + 1, kept monotone and at most 1.
std::vector<double> holmAdjust(const std::vector<double>& p);

}  // namespace lidarcal
