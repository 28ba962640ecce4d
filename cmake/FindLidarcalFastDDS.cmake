# SPDX-License-Identifier: BSD-3-Clause
# Finds Debian's eProsima Fast DDS (libfastrtps-dev: fastdds/dds/... headers, libfastrtps and
# libfastcdr) and its IDL compiler (fastddsgen) for the other vendor of the ROS 2 node's
# cross-vendor test. Looked up piece by piece, like the ROS1 libraries.
#
# Sets LidarcalFastDDS_FOUND, LidarcalFastDDS_INCLUDE_DIRS, LidarcalFastDDS_LIBRARIES (full
# paths), LidarcalFastDDS_GEN (the fastddsgen program) and LidarcalFastDDS_MISSING.

set(LidarcalFastDDS_MISSING "")
set(LidarcalFastDDS_INCLUDE_DIRS "")
set(LidarcalFastDDS_LIBRARIES "")

include(${CMAKE_CURRENT_LIST_DIR}/LidarcalFindPieces.cmake)
lidarcal_find_headers(LidarcalFastDDS LIDARCAL_FASTDDS_HDR fastdds/dds/domain/DomainParticipantFactory.hpp
                      fastcdr/Cdr.h)
lidarcal_find_libraries(LidarcalFastDDS LIDARCAL_FASTDDS_LIB fastrtps fastcdr)
find_program(LidarcalFastDDS_GEN NAMES fastddsgen)
mark_as_advanced(LidarcalFastDDS_GEN)
if(NOT LidarcalFastDDS_GEN)
  list(APPEND LidarcalFastDDS_MISSING "fastddsgen")
endif()
lidarcal_find_finish(LidarcalFastDDS)
