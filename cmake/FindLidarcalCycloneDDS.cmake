# SPDX-License-Identifier: BSD-3-Clause
# Finds Debian's Eclipse Cyclone DDS (cyclonedds-dev: dds/dds.h, libddsc) and its IDL compiler
# (cyclonedds-tools: idlc) for the ROS 2 node `lidarcal_ros2_node`. Looked up piece by piece
# like the ROS1 libraries, so that the message names the missing pieces.
#
# Sets LidarcalCycloneDDS_FOUND, LidarcalCycloneDDS_INCLUDE_DIRS, LidarcalCycloneDDS_LIBRARIES
# (full paths), LidarcalCycloneDDS_IDLC (the idlc program) and LidarcalCycloneDDS_MISSING.

set(LidarcalCycloneDDS_MISSING "")
set(LidarcalCycloneDDS_INCLUDE_DIRS "")
set(LidarcalCycloneDDS_LIBRARIES "")

include(${CMAKE_CURRENT_LIST_DIR}/LidarcalFindPieces.cmake)
lidarcal_find_headers(LidarcalCycloneDDS LIDARCAL_CYCLONE_HDR dds/dds.h)
lidarcal_find_libraries(LidarcalCycloneDDS LIDARCAL_CYCLONE_LIB ddsc)
find_program(LidarcalCycloneDDS_IDLC NAMES idlc)
mark_as_advanced(LidarcalCycloneDDS_IDLC)
if(NOT LidarcalCycloneDDS_IDLC)
  list(APPEND LidarcalCycloneDDS_MISSING "idlc (cyclonedds-tools)")
endif()
lidarcal_find_finish(LidarcalCycloneDDS)
