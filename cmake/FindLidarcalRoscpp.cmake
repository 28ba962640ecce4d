# SPDX-License-Identifier: BSD-3-Clause
# Finds Debian's roscpp (libroscpp-dev) for the live correction node `lidarcal_node`, on top of
# the bag libraries (FindLidarcalRosbag.cmake), and the message headers its watch and learn modes
# publish: diagnostic_msgs/DiagnosticArray (libdiagnostic-msgs-dev: the /diagnostics status) and
# std_msgs/String (libstd-msgs-dev: learn mode's candidate model). Odometry and tf come from the
# bag libraries' nav_msgs and tf2_msgs. Like those, looked up piece by piece: Debian's ROS1
# packages ship no usable CMake config outside catkin.
#
# Sets LidarcalRoscpp_FOUND, LidarcalRoscpp_INCLUDE_DIRS, LidarcalRoscpp_LIBRARIES (full paths),
# LidarcalRoscpp_MISSING and LidarcalRoscpp_ROSMASTER (the rosmaster program, for the node test;
# empty when python3-rosmaster is not installed).

set(LidarcalRoscpp_MISSING "")
set(LidarcalRoscpp_INCLUDE_DIRS "")
set(LidarcalRoscpp_LIBRARIES "")

include(${CMAKE_CURRENT_LIST_DIR}/LidarcalFindPieces.cmake)
lidarcal_find_headers(LidarcalRoscpp LIDARCAL_ROSCPP_HDR ros/ros.h ros/console.h xmlrpcpp/XmlRpc.h
                      diagnostic_msgs/DiagnosticArray.h std_msgs/String.h)
lidarcal_find_libraries(LidarcalRoscpp LIDARCAL_ROSCPP_LIB roscpp rosconsole xmlrpcpp roscpp_serialization rostime
                        cpp_common boost_system boost_thread)

find_program(LidarcalRoscpp_ROSMASTER NAMES rosmaster)
mark_as_advanced(LidarcalRoscpp_ROSMASTER)
if(NOT LidarcalRoscpp_ROSMASTER)
  set(LidarcalRoscpp_ROSMASTER "")
endif()

lidarcal_find_finish(LidarcalRoscpp)
