// SPDX-License-Identifier: BSD-3-Clause
// Stand-in for import_rosbag.cpp when lidarcal is built without the ROS1 libraries.

#include "io/import_rosbag.hpp"
#include "io/rosbag_rewrite.hpp"

#include "common/errors.hpp"

namespace lidarcal::io {
namespace {
[[noreturn]] void unavailable(const std::filesystem::path& file) {
  throw InputError(file.string(), "--from rosbag1",
                   "this lidarcal was built without ROS1 bag support",
                   "install librosbag-storage-dev and libsensor-msgs-dev (scripts/install-deps.sh) "
                   "and configure "
                   "with -DLIDARCAL_WITH_ROSBAG=ON, or convert the bag to CSV (docs/FORMAT.md)");
}
}  // namespace

bool rosbagSupported() { return false; }
void requireRosbagSupport(const std::filesystem::path& bag) { unavailable(bag); }

std::vector<BagTopic> listBagTopics(const std::filesystem::path& bag) { unavailable(bag); }

ImportReport readRosbag(const std::filesystem::path& bag, const RosbagConfig&,
                        const ScanCallback&) {
  unavailable(bag);
}

BagRewriteReport rewriteRosbag(const std::filesystem::path& in, const std::filesystem::path&,
                               const std::string&, const RangesCallback&) {
  unavailable(in);
}

BagRewriteReport rewriteRosbagTopics(const std::filesystem::path& in, const std::filesystem::path&,
                                     const std::vector<std::string>&, const TopicRangesCallback&) {
  unavailable(in);
}

}  // namespace lidarcal::io
