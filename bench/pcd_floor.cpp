// SPDX-License-Identifier: BSD-3-Clause
// The I/O floor of a sequence (docs/results/speed.md): read every .pcd file of a directory with PCL
// and write it again, binary, into another directory. What any command that rewrites the scans must
// at least do; bench/speed.sh times lidarcal's commands against it. OUT_DIR is made anew, a
// directory left by a previous run removed first, as lidarcal's commands do with --overwrite:
// creating files in a fresh directory costs the file system more than overwriting old ones (on
// ext4, about 0.7 ms against 0.15 ms per file here), and the floor must pay what they pay.
//
//   pcd_floor IN_DIR OUT_DIR

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: pcd_floor IN_DIR OUT_DIR\n");
    return 2;
  }
  namespace fs = std::filesystem;
  const fs::path in = argv[1], out = argv[2];
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(in))
    if (e.path().extension() == ".pcd") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  fs::remove_all(out);
  fs::create_directories(out);
  pcl::PCDReader reader;
  pcl::PCDWriter writer;
  for (const auto& f : files) {
    pcl::PCLPointCloud2 cloud;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    if (reader.read(f.string(), cloud, origin, orientation, version) != 0) {
      std::fprintf(stderr, "pcd_floor: cannot read %s\n", f.c_str());
      return 1;
    }
    if (writer.writeBinary((out / f.filename()).string(), cloud, origin, orientation) != 0) {
      std::fprintf(stderr, "pcd_floor: cannot write %s\n", (out / f.filename()).c_str());
      return 1;
    }
  }
  std::printf("%zu scans\n", files.size());
  return 0;
}
