# SPDX-License-Identifier: AGPL-3.0-or-later
# Installation and packaging of libhmc (issue 10), included by the top-level
# CMakeLists.txt after the library and the tools are defined.
#
# `cmake --install BUILD [--prefix DIR]` installs:
#   include/hmc/*.h, *.hpp          the public headers (C API hmc.h, hmc.hpp, C++ API)
#   lib/libhmc.a                    hmc::hmc_static (links TetGen and zlib: carried by both packages)
#   lib/libhmc.so*                  hmc::hmc_shared (with HMC_BUILD_SHARED, the default)
#   bin/hmc                         the command line (with HMC_BUILD_TOOLS)
#   lib/cmake/hmc/                  find_package(hmc): hmc::hmc, hmc::hmc_static, hmc::hmc_shared, version file
#   lib/pkgconfig/hmc.pc            pkg-config (relocatable: paths relative to the .pc file)
#
# The project itself keeps using the static `hmc` target (hmc::hmc in this
# tree); the installed libraries are built from its object files, so
# nothing is compiled twice.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

option(HMC_BUILD_SHARED "Build and install libhmc as a shared library too" ON)
set(HMC_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/hmc CACHE STRING "Where to install the CMake package files")

set(HMC_PUBLIC_INCLUDE ${PROJECT_SOURCE_DIR}/libhmc/include)
set(HMC_INSTALLED_LIBRARIES hmc_static)

add_library(hmc_static STATIC $<TARGET_OBJECTS:hmc>)
set_target_properties(hmc_static PROPERTIES
  OUTPUT_NAME hmc EXPORT_NAME hmc_static LINKER_LANGUAGE CXX
  ARCHIVE_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/lib)
target_include_directories(hmc_static INTERFACE
  $<BUILD_INTERFACE:${HMC_PUBLIC_INCLUDE}> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
# A static library's users link its dependencies: the installed package
# finds them again (hmc::zlib, hmc::tetgen in hmc-config.cmake).
target_link_libraries(hmc_static INTERFACE
  $<BUILD_INTERFACE:ZLIB::ZLIB> $<BUILD_INTERFACE:hmc_tetgen>
  $<INSTALL_INTERFACE:hmc::zlib> $<INSTALL_INTERFACE:hmc::tetgen>)

if(HMC_BUILD_SHARED)
  add_library(hmc_shared SHARED $<TARGET_OBJECTS:hmc>)
  # While the major version is 0, every minor version may change the ABI.
  if(PROJECT_VERSION_MAJOR EQUAL 0)
    set(HMC_SOVERSION 0.${PROJECT_VERSION_MINOR})
  else()
    set(HMC_SOVERSION ${PROJECT_VERSION_MAJOR})
  endif()
  set_target_properties(hmc_shared PROPERTIES
    OUTPUT_NAME hmc EXPORT_NAME hmc_shared LINKER_LANGUAGE CXX
    VERSION ${PROJECT_VERSION} SOVERSION ${HMC_SOVERSION}
    LIBRARY_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/lib)
  target_include_directories(hmc_shared INTERFACE
    $<BUILD_INTERFACE:${HMC_PUBLIC_INCLUDE}> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(hmc_shared PRIVATE ZLIB::ZLIB hmc_tetgen)
  # Every symbol resolved at link time (not with sanitizers: their runtime
  # comes with the executable).
  if(CMAKE_SYSTEM_NAME STREQUAL "Linux" AND NOT HMC_SANITIZE AND NOT HMC_BUILD_FUZZ)
    target_link_options(hmc_shared PRIVATE LINKER:--no-undefined)
  endif()
  list(APPEND HMC_INSTALLED_LIBRARIES hmc_shared)
endif()

install(TARGETS ${HMC_INSTALLED_LIBRARIES} EXPORT hmcTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${HMC_PUBLIC_INCLUDE}/hmc DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp")
if(TARGET hmc_cli)
  install(TARGETS hmc_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

# CMake package: hmc-config.cmake, hmc-config-version.cmake, hmc-targets*.cmake.
install(EXPORT hmcTargets NAMESPACE hmc:: FILE hmc-targets.cmake DESTINATION ${HMC_INSTALL_CMAKEDIR})
get_filename_component(HMC_TETGEN_LIBRARY_DIR "${TETGEN_LIBRARY}" DIRECTORY)
set(HMC_CXX_RUNTIME "stdc++ m")  # for C-only users of the static library (GNU and Clang with libstdc++)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hmc-config.cmake.in
  ${PROJECT_BINARY_DIR}/hmc-config.cmake INSTALL_DESTINATION ${HMC_INSTALL_CMAKEDIR})
# 0.x: a new minor version is incompatible; from 1.0 on, same major.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(HMC_COMPATIBILITY SameMinorVersion)
else()
  set(HMC_COMPATIBILITY SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hmc-config-version.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${HMC_COMPATIBILITY})
install(FILES ${PROJECT_BINARY_DIR}/hmc-config.cmake ${PROJECT_BINARY_DIR}/hmc-config-version.cmake
  DESTINATION ${HMC_INSTALL_CMAKEDIR})

# pkg-config: prefix relative to the .pc file, so that the package works
# wherever it is installed (cmake --install --prefix DIR).
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(HMC_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
  set(HMC_PC_LIBDIR "${CMAKE_INSTALL_LIBDIR}")
else()
  file(RELATIVE_PATH HMC_PC_UP "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
  string(REGEX REPLACE "/$" "" HMC_PC_UP "${HMC_PC_UP}")
  set(HMC_PC_PREFIX "\${pcfiledir}/${HMC_PC_UP}")
  set(HMC_PC_LIBDIR "\${prefix}/${CMAKE_INSTALL_LIBDIR}")
endif()
if(IS_ABSOLUTE "${CMAKE_INSTALL_INCLUDEDIR}")
  set(HMC_PC_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}")
else()
  set(HMC_PC_INCLUDEDIR "\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/hmc.pc.in ${PROJECT_BINARY_DIR}/hmc.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/hmc.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
