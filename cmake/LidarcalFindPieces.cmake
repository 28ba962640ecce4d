# SPDX-License-Identifier: BSD-3-Clause
# Helpers of the Find modules that look up Debian's ROS1 libraries piece by piece
# (FindLidarcalRosbag.cmake, FindLidarcalRoscpp.cmake).

# lidarcal_find_headers(<prefix> <cache_prefix> spec...): each spec is a header, or HEADER@SUBDIR
# when the ROS headers expect SUBDIR (under an include root) on the include path too. Found
# directories are appended to <prefix>_INCLUDE_DIRS, missing headers to <prefix>_MISSING.
macro(lidarcal_find_headers prefix cache_prefix)
  foreach(spec ${ARGN})
    string(REPLACE "@" ";" parts "${spec}")
    list(GET parts 0 header)
    set(sub "")
    list(LENGTH parts n)
    if(n GREATER 1)
      list(GET parts 1 sub)
    endif()
    string(MAKE_C_IDENTIFIER "${cache_prefix}_${header}" var)
    find_path(${var} NAMES ${header} PATH_SUFFIXES ${sub})
    mark_as_advanced(${var})
    if(${var})
      list(APPEND ${prefix}_INCLUDE_DIRS "${${var}}")
    else()
      list(APPEND ${prefix}_MISSING "${header}")
    endif()
  endforeach()
endmacro()

# lidarcal_find_libraries(<prefix> <cache_prefix> lib...): find_library for each (cached as
# <cache_prefix>_<lib>); full paths are appended to <prefix>_LIBRARIES, the missing ones (as
# lib<name>) to <prefix>_MISSING.
macro(lidarcal_find_libraries prefix cache_prefix)
  foreach(lib ${ARGN})
    find_library(${cache_prefix}_${lib} NAMES ${lib})
    mark_as_advanced(${cache_prefix}_${lib})
    if(${cache_prefix}_${lib})
      list(APPEND ${prefix}_LIBRARIES "${${cache_prefix}_${lib}}")
    else()
      list(APPEND ${prefix}_MISSING "lib${lib}")
    endif()
  endforeach()
endmacro()

# lidarcal_find_finish(<prefix>): <prefix>_FOUND is true when nothing is missing.
macro(lidarcal_find_finish prefix)
  list(REMOVE_DUPLICATES ${prefix}_INCLUDE_DIRS)
  if(${prefix}_MISSING)
    set(${prefix}_FOUND FALSE)
  else()
    set(${prefix}_FOUND TRUE)
  endif()
endmacro()
