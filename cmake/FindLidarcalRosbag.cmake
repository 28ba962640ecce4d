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

# Header -> extra include directory that the ROS headers expect on the path.
foreach(pair
    "rosbag/view.h;"
    "sensor_msgs/LaserScan.h;"
    "nav_msgs/Odometry.h;"
    "tf2_msgs/TFMessage.h;"
    "pluginlib/class_loader.hpp;pluginlib"
    "class_loader/class_loader.hpp;class_loader"
    "rcpputils/filesystem_helper.hpp;rcpputils"
    "rcutils/types.h;rcutils"
    "ament_index_cpp/get_package_prefix.hpp;ament_index_cpp")
  list(GET pair 0 header)
  list(LENGTH pair n)
  set(sub "")
  if(n GREATER 1)
    list(GET pair 1 sub)
  endif()
  string(MAKE_C_IDENTIFIER "LIDARCAL_ROS_HDR_${header}" var)
  find_path(${var} NAMES ${header} PATH_SUFFIXES ${sub})
  mark_as_advanced(${var})
  if(${var})
    list(APPEND LidarcalRosbag_INCLUDE_DIRS "${${var}}")
  else()
    list(APPEND LidarcalRosbag_MISSING "${header}")
  endif()
endforeach()

foreach(lib rosbag_storage roslz4 cpp_common rostime console_bridge boost_filesystem
            class_loader ament_index_cpp rcutils rcpputils roscpp_serialization)
  find_library(LIDARCAL_ROS_LIB_${lib} NAMES ${lib})
  mark_as_advanced(LIDARCAL_ROS_LIB_${lib})
  if(LIDARCAL_ROS_LIB_${lib})
    list(APPEND LidarcalRosbag_LIBRARIES "${LIDARCAL_ROS_LIB_${lib}}")
  else()
    list(APPEND LidarcalRosbag_MISSING "lib${lib}")
  endif()
endforeach()

list(REMOVE_DUPLICATES LidarcalRosbag_INCLUDE_DIRS)
if(LidarcalRosbag_MISSING)
  set(LidarcalRosbag_FOUND FALSE)
else()
  set(LidarcalRosbag_FOUND TRUE)
endif()
