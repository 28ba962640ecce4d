# SPDX-License-Identifier: BSD-3-Clause
# Installation: `cmake --install build [--prefix P]` puts
#   bin/lidarcal
#   lib/liblidarcal_<name>.a                  every library made by lidarcal_library()
#   include/lidarcal/<folder>/*.hpp          their headers (#include "io/sequence.hpp")
#   share/lidarcal/                           the bundled data (scenes, example sequence)
#   lib/cmake/lidarcal/lidarcalConfig.cmake   find_package(lidarcal) -> targets lidarcal::<name>
include(CMakePackageConfigHelpers)

install(TARGETS lidarcal RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY "${PROJECT_SOURCE_DIR}/data/" DESTINATION ${CMAKE_INSTALL_DATADIR}/lidarcal)

set(LIDARCAL_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/lidarcal)
install(EXPORT lidarcalTargets NAMESPACE lidarcal:: DESTINATION ${LIDARCAL_CMAKE_DIR})
configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/lidarcalConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/lidarcalConfig.cmake" INSTALL_DESTINATION ${LIDARCAL_CMAKE_DIR}
  PATH_VARS CMAKE_INSTALL_DATADIR)
write_basic_package_version_file("${PROJECT_BINARY_DIR}/lidarcalConfigVersion.cmake"
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/lidarcalConfig.cmake" "${PROJECT_BINARY_DIR}/lidarcalConfigVersion.cmake"
  DESTINATION ${LIDARCAL_CMAKE_DIR})
