# SPDX-License-Identifier: BSD-3-Clause
# Finds Debian's ROS1 bag-reading libraries (librosbag-storage-dev, libsensor-msgs-dev,
# libnav-msgs-dev and libtf2-msgs-dev for `import --pose odom:|tf:`, and the
# packages Debian forgets to pull in: libclass-loader-dev, librcpputils-dev, librcutils-dev,
# libament-index-cpp-dev). rosbag_storage's pkg-config file is broken on Debian 12 (it requires
# a pluginlib.pc that is not shipped), so headers and libraries are looked up one by one.
#
# Sets LidarcalRosbag_FOUND, LidarcalRosbag_INCLUDE_DIRS, LidarcalRosbag_LIBRARIES (full paths)
# and LidarcalRosbag_MISSING (what was not found, for the message).

set(LidarcalRosbag_MISSING "")
set(LidarcalRosbag_INCLUDE_DIRS "")
set(LidarcalRosbag_LIBRARIES "")

include(${CMAKE_CURRENT_LIST_DIR}/LidarcalFindPieces.cmake)
# HEADER@DIR: the ROS headers also expect DIR on the include path.
lidarcal_find_headers(LidarcalRosbag LIDARCAL_ROS_HDR rosbag/view.h sensor_msgs/LaserScan.h nav_msgs/Odometry.h
                      tf2_msgs/TFMessage.h pluginlib/class_loader.hpp@pluginlib class_loader/class_loader.hpp@class_loader
                      rcpputils/filesystem_helper.hpp@rcpputils rcutils/types.h@rcutils
                      ament_index_cpp/get_package_prefix.hpp@ament_index_cpp)
lidarcal_find_libraries(LidarcalRosbag LIDARCAL_ROS_LIB rosbag_storage roslz4 cpp_common rostime console_bridge
                        boost_filesystem class_loader ament_index_cpp rcutils rcpputils roscpp_serialization)
lidarcal_find_finish(LidarcalRosbag)
