// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Uniform dequantisation (Theis, van den Oord & Bethge, "A note on the evaluation of generative
// models", ICLR 2016). Readings on a grid q are scored as densities at the reading plus a uniform
// draw over its grid cell: a continuous density taken at the grid points themselves is not
// comparable with the rounded model's cell probability (where the noise is finer than the grid it
// is higher than any probability over q allows); on the spread readings both are densities of
// the same variable, and the rounded model is the true one when the readings were rounded. Fits
// stay on the readings as recorded.

#include <cstdint>
#include <vector>

namespace lidarcal::diagnosis {

/// Adds to each reading, in order, a uniform draw over [-q/2, q/2] from a stream seeded by `seed`.
void dequantise(std::vector<double>& readings, double q, std::uint64_t seed);

}  // namespace lidarcal::diagnosis
