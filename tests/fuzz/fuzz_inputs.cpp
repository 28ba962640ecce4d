// SPDX-License-Identifier: BSD-3-Clause
#include "fuzz_inputs.hpp"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <set>

#include "common/errors.hpp"
#include "io/import_carmen.hpp"
#include "io/import_csv.hpp"
#include "io/import_rosbag2.hpp"
#include "io/import_ydlidar.hpp"
#include "io/landmarks_csv.hpp"
#include "io/mcap_reader.hpp"
#include "io/model_io.hpp"
#include "io/noise_json.hpp"
#include "io/observations_csv.hpp"
#include "io/pcd_scan.hpp"
#include "io/ros2_msgs.hpp"
#include "io/scene_io.hpp"
#include "io/sequence.hpp"
#include "io/true_ranges.hpp"

namespace lidarcal::fuzz {
namespace {

namespace fs = std::filesystem;

/// A scratch file per process (the readers take paths), rewritten for every input.
class Scratch {
 public:
  explicit Scratch(const std::string& name)
      : path_(fs::temp_directory_path() /
              ("lidarcal-fuzz-" + std::to_string(::getpid()) + "-" + name)) {}
  ~Scratch() {
    std::error_code ec;
    fs::remove(path_, ec);
  }
  const fs::path& write(const std::uint8_t* data, std::size_t size) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    return path_;
  }

 private:
  fs::path path_;
};

/// Runs `read`; a clean InputError is an accepted outcome.
template <typename F>
void expectResultOrInputError(F&& read) {
  try {
    read();
  } catch (const InputError&) {
  }
}

void pcd(const std::uint8_t* data, std::size_t size) {
  static Scratch file("scan.pcd");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] { io::readScanHeader(p); });
  expectResultOrInputError([&] { io::readScan(p); });
}

void json(const std::uint8_t* data, std::size_t size) {
  static Scratch file("file.json");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] { io::readScene(p); });
  expectResultOrInputError([&] { io::readModel(p); });
  expectResultOrInputError([&] { io::readTruth(p); });
  expectResultOrInputError([&] { io::readSequenceMeta(p); });
  expectResultOrInputError([&] { io::readObservationScene(p); });
  expectResultOrInputError([&] { io::readNoiseSetting(p); });
  expectResultOrInputError([&] { io::readNoiseTruth(p); });
}

void csv(const std::uint8_t* data, std::size_t size) {
  static Scratch file("table.csv");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] { io::readTrueRanges(p); });
  expectResultOrInputError([&] { io::readLandmarksCsv(p); });
  expectResultOrInputError([&] { io::readObservations(p); });
  expectResultOrInputError([&] { io::readOdometry(p); });
}

/// Every scan an importer hands on must be consistent (one angle per range).
bool checkScan(const io::RawScan& s) {
  if (s.angles_rad.size() != s.ranges_m.size())
    throw std::logic_error("importer: angles and ranges differ in number");
  if (!s.intensities.empty() && s.intensities.size() != s.ranges_m.size())
    throw std::logic_error("importer: intensities and ranges differ in number");
  return true;
}

void carmen(const std::uint8_t* data, std::size_t size) {
  static Scratch file("log.txt");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] { io::readCarmenLog(p, io::CarmenConfig{}, checkScan); });
  io::CarmenConfig odometry;
  odometry.pose = io::CarmenPose::odometry;
  expectResultOrInputError([&] { io::readCarmenLog(p, odometry, checkScan); });
}

void ydlidar(const std::uint8_t* data, std::size_t size) {
  static Scratch file("scans.dat");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] { io::readYdlidarDat(p, io::YdlidarConfig{}, checkScan); });
}

void csvImport(const std::uint8_t* data, std::size_t size) {
  static Scratch file("scans.csv");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] { io::readCsvScans(p, io::CsvConfig{}, checkScan); });
}

/// The MCAP reader (every message of every channel, merged in log-time order) and the ROS 2
/// importer on it: the only LaserScan topic, and with --pose odom:/odom.
void mcap(const std::uint8_t* data, std::size_t size) {
  static Scratch file("bag.mcap");
  const auto& p = file.write(data, size);
  expectResultOrInputError([&] {
    const io::McapReader reader(p);
    std::set<std::string> all;
    for (const auto& c : reader.channels()) all.insert(c.topic);
    std::uint64_t sum = 0;
    reader.forEachMessage(all, [&](const io::McapMessage& m) {
      // every byte handed on must be readable (ASan)
      for (std::size_t i = 0; i < m.size; ++i) sum += m.data[i];
      return true;
    });
  });
  expectResultOrInputError([&] { io::readRosbag2(p, io::RosbagConfig{}, checkScan); });
  io::RosbagConfig odom;
  odom.pose.kind = io::BagPoseConfig::Kind::odom;
  odom.pose.name = "/odom";
  expectResultOrInputError([&] { io::readRosbag2(p, odom, checkScan); });
}

/// The CDR decoders of the three ROS 2 messages read, on the same bytes.
void cdr(const std::uint8_t* data, std::size_t size) {
  io::Ros2LaserScan scan;
  expectResultOrInputError([&] { io::decodeLaserScan(data, size, scan); });
  expectResultOrInputError([&] { io::decodeOdometry(data, size); });
  expectResultOrInputError([&] { io::decodeTfMessage(data, size); });
}

}  // namespace

const std::vector<NamedTarget>& targets() {
  static const std::vector<NamedTarget> all = {{"pcd", pcd},         {"json", json},
                                               {"csv", csv},         {"carmen", carmen},
                                               {"ydlidar", ydlidar}, {"csv_import", csvImport},
                                               {"mcap", mcap},       {"cdr", cdr}};
  return all;
}

}  // namespace lidarcal::fuzz
