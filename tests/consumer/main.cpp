// SPDX-License-Identifier: BSD-3-Clause
// Uses the installed lidarcal::io: opens the bundled example sequence from share/lidarcal and
// writes a small sequence with the importers' SequenceWriter; and lidarcal::calibration: corrects
// one range with a model.json, as a driver would (docs/FORMAT.md, "Model for drivers"). Exit 0
// when all is as expected.

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "calibration/filtering.hpp"
#include "io/model_io.hpp"
#include "io/sequence.hpp"
#include "io/sequence_writer.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  using namespace lidarcal;
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer WORK_DIR\n");
    return 2;
  }
  const io::Sequence example = io::openSequence(fs::path(LIDARCAL_DATA) / "example" / "scans");
  std::printf("example: %zu scans, %zu stops\n", example.scans.size(), example.stops.size());
  if (example.scans.size() != 100 || example.stops.size() != 10) return 1;

  const fs::path out = fs::path(argv[1]) / "consumer-seq";
  fs::remove_all(out);
  io::SequenceWriter writer(out, {});
  io::RawScan scan;
  for (int i = 0; i < 4; ++i) {
    scan.angles_rad.push_back(i * kPi / 2);
    scan.ranges_m.push_back(2.0f);
  }
  writer.add(scan);
  writer.commit("consumer");
  const io::Scan back = io::readScan(out / io::scanFileName(0));
  std::printf("wrote and read back %zu points\n", back.cloud->size());
  if (back.cloud->size() != 4 || std::abs((*back.cloud)[1].y - 2.0f) > 1e-6f) return 1;

  // Correcting one range: f(d) = 0.03 + 0.98 d + 0.004 d^2 fitted over 0.5-8 m, so the reading
  // f(3) = 3.006 is corrected to 3 m.
  CalibrationModel written;
  written.model.bias.alpha = {0.03, 0.98, 0.004};
  written.model.range_min_m = 0.15;
  written.model.range_max_m = 12.0;
  written.fitted_range_m = std::make_pair(0.5, 8.0);
  io::writeModel(fs::path(argv[1]) / "consumer-model.json", written);

  const CalibrationModel model = io::readModel(fs::path(argv[1]) / "consumer-model.json");
  const calibration::ReadingCorrector correct = calibration::readingCorrector(
      model, calibration::InversionMethod::ls, calibration::Outside::keep);
  const calibration::CorrectedReading c = correct(3.006);
  std::printf("reading 3.006 m -> %.6f m\n", c.range_m);
  return c.fate == calibration::ReadingFate::corrected && std::abs(c.range_m - 3.0) < 1e-9 ? 0 : 1;
}
