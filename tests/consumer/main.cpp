// Uses the installed lidarcal::io: opens the bundled example sequence from share/lidarcal and
// writes a small sequence with the importers' SequenceWriter. Exit 0 when all is as expected.

#include <cmath>
#include <cstdio>
#include <filesystem>

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
  return back.cloud->size() == 4 && std::abs((*back.cloud)[1].y - 2.0f) < 1e-6f ? 0 : 1;
}
