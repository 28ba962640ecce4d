# Finds Debian's roscpp (libroscpp-dev) for the live correction node `lidarcal_node`, on top of
# the bag libraries (FindLidarcalRosbag.cmake). Like those, looked up piece by piece: Debian's
# ROS1 packages ship no usable CMake config outside catkin.
#
# Sets LidarcalRoscpp_FOUND, LidarcalRoscpp_INCLUDE_DIRS, LidarcalRoscpp_LIBRARIES (full paths),
# LidarcalRoscpp_MISSING and LidarcalRoscpp_ROSMASTER (the rosmaster program, for the node test;
# empty when python3-rosmaster is not installed).

set(LidarcalRoscpp_MISSING "")
set(LidarcalRoscpp_INCLUDE_DIRS "")
set(LidarcalRoscpp_LIBRARIES "")

foreach(header ros/ros.h ros/console.h xmlrpcpp/XmlRpc.h)
  string(MAKE_C_IDENTIFIER "LIDARCAL_ROSCPP_HDR_${header}" var)
  find_path(${var} NAMES ${header})
  mark_as_advanced(${var})
  if(${var})
    list(APPEND LidarcalRoscpp_INCLUDE_DIRS "${${var}}")
  else()
    list(APPEND LidarcalRoscpp_MISSING "${header}")
  endif()
endforeach()

foreach(lib roscpp rosconsole xmlrpcpp roscpp_serialization rostime cpp_common boost_system boost_thread)
  find_library(LIDARCAL_ROSCPP_LIB_${lib} NAMES ${lib})
  mark_as_advanced(LIDARCAL_ROSCPP_LIB_${lib})
  if(LIDARCAL_ROSCPP_LIB_${lib})
    list(APPEND LidarcalRoscpp_LIBRARIES "${LIDARCAL_ROSCPP_LIB_${lib}}")
  else()
    list(APPEND LidarcalRoscpp_MISSING "lib${lib}")
  endif()
endforeach()

find_program(LidarcalRoscpp_ROSMASTER NAMES rosmaster)
mark_as_advanced(LidarcalRoscpp_ROSMASTER)
if(NOT LidarcalRoscpp_ROSMASTER)
  set(LidarcalRoscpp_ROSMASTER "")
endif()

list(REMOVE_DUPLICATES LidarcalRoscpp_INCLUDE_DIRS)
if(LidarcalRoscpp_MISSING)
  set(LidarcalRoscpp_FOUND FALSE)
else()
  set(LidarcalRoscpp_FOUND TRUE)
endif()
