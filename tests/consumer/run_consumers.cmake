# SPDX-License-Identifier: AGPL-3.0-or-later
# test_consumer (cmake -P): installs the build into a prefix inside the
# build tree, makes a stream with the installed `hmc gen` + `hmc enc`, then
# builds and runs, out of tree and against the installed files only:
#   cmake/     C++ (hmc.hpp, codec.hpp) through find_package(hmc): shared, then static
#   cmake_c/   C99 (hmc.h) through find_package(hmc), static, in a C-only project
#   pkgconfig/ C99 (hmc.h) through pkg-config: shared, then static (libhmc.a
#              with the Libs.private of hmc.pc)
# Variables: HMC_BUILD_DIR HMC_WORK_DIR HMC_CONSUMER_SOURCE HMC_GENERATOR
# HMC_C_COMPILER HMC_CXX_COMPILER HMC_LIBDIR HMC_VERSION, and optionally
# HMC_PKG_CONFIG, HMC_CONSUMER_FLAGS (sanitizer flags of the build) and
# HMC_SHARED (OFF: the build has no shared library; static variants only).
cmake_minimum_required(VERSION 3.18)
foreach(v HMC_BUILD_DIR HMC_WORK_DIR HMC_CONSUMER_SOURCE HMC_GENERATOR HMC_C_COMPILER HMC_CXX_COMPILER
          HMC_LIBDIR HMC_VERSION)
  if(NOT DEFINED ${v} OR "${${v}}" STREQUAL "")
    message(FATAL_ERROR "run_consumers.cmake: ${v} is not set")
  endif()
endforeach()
separate_arguments(flags UNIX_COMMAND "${HMC_CONSUMER_FLAGS}")
if(NOT DEFINED HMC_SHARED)
  set(HMC_SHARED ON)
endif()

# hmc_run(WHAT COMMAND...): run, fail the test with the output on error;
# the standard output is left in HMC_OUT.
function(hmc_run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "${what} failed (${rc}):\n  ${cmd}\n${out}\n${err}")
  endif()
  set(HMC_OUT "${out}" PARENT_SCOPE)
  message(STATUS "${what}: ok")
endfunction()

function(hmc_expect what text pattern)
  if(NOT text MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected output matching '${pattern}', got:\n${text}")
  endif()
endfunction()

# readelf -d: whether a program needs libhmc.so at run time.
find_program(READELF readelf)
function(hmc_check_needs what program expect)
  if(NOT READELF)
    return()
  endif()
  execute_process(COMMAND ${READELF} -d ${program} OUTPUT_VARIABLE dyn RESULT_VARIABLE rc)
  if(dyn MATCHES "NEEDED[^\n]*libhmc\\.so")
    set(needs TRUE)
  else()
    set(needs FALSE)
  endif()
  if(NOT needs STREQUAL expect)
    message(FATAL_ERROR "${what}: needs libhmc.so = ${needs}, expected ${expect}\n${dyn}")
  endif()
endfunction()

set(work ${HMC_WORK_DIR})
set(prefix ${work}/prefix)
file(REMOVE_RECURSE ${work})
file(MAKE_DIRECTORY ${work})

# 1. Install.
hmc_run("cmake --install" ${CMAKE_COMMAND} --install ${HMC_BUILD_DIR} --prefix ${prefix})
set(libdir ${prefix}/${HMC_LIBDIR})
foreach(f include/hmc/hmc.h include/hmc/hmc.hpp include/hmc/codec.hpp include/hmc/status.hpp
          include/hmc/mesh.hpp bin/hmc ${HMC_LIBDIR}/libhmc.a ${HMC_LIBDIR}/pkgconfig/hmc.pc
          ${HMC_LIBDIR}/cmake/hmc/hmc-config.cmake ${HMC_LIBDIR}/cmake/hmc/hmc-config-version.cmake
          ${HMC_LIBDIR}/cmake/hmc/hmc-targets.cmake)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${prefix}/${f}")
  endif()
endforeach()
file(GLOB shared_libs ${libdir}/libhmc.so*)
if(HMC_SHARED AND NOT shared_libs)
  message(FATAL_ERROR "not installed: ${libdir}/libhmc.so")
endif()
file(GLOB internal ${prefix}/include/hmc/*/*)
if(internal)
  message(FATAL_ERROR "internal headers installed: ${internal}")
endif()

# 2. A stream, made by the installed program.
set(stream ${work}/torus.hmc)
hmc_run("hmc gen" ${prefix}/bin/hmc gen torus --vertices 3000 -o ${work}/torus.ply)
hmc_run("hmc enc" ${prefix}/bin/hmc enc ${work}/torus.ply -o ${stream} --levels 3)

# 3. C++ through find_package(hmc): the shared library, then the static one.
set(variants ON)
if(HMC_SHARED)
  set(variants OFF ON)
endif()
foreach(static ${variants})
  set(bin ${work}/cxx-static-${static})
  hmc_run("find_package consumer (static ${static}): configure"
          ${CMAKE_COMMAND} -S ${HMC_CONSUMER_SOURCE}/cmake -B ${bin} -G ${HMC_GENERATOR}
          -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${HMC_CXX_COMPILER}
          -DCMAKE_PREFIX_PATH=${prefix} -DHMC_EXPECT_PREFIX=${prefix} -Dhmc_USE_STATIC_LIBS=${static}
          "-DCMAKE_CXX_FLAGS=${HMC_CONSUMER_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${HMC_CONSUMER_FLAGS}")
  hmc_run("find_package consumer (static ${static}): build" ${CMAKE_COMMAND} --build ${bin})
  hmc_run("find_package consumer (static ${static}): run" ${bin}/consumer_cxx ${stream})
  hmc_expect("consumer_cxx" "${HMC_OUT}" "level 0: [0-9]+ vertices, [1-9][0-9]* triangles")
  hmc_expect("consumer_cxx" "${HMC_OUT}" "consumer_cxx: 3 levels, libhmc ${HMC_VERSION}")
  if(static)
    hmc_check_needs("consumer_cxx (static)" ${bin}/consumer_cxx FALSE)
  else()
    hmc_check_needs("consumer_cxx (shared)" ${bin}/consumer_cxx TRUE)
  endif()
  message(STATUS "${HMC_OUT}")
endforeach()

# 4. C through find_package(hmc), static: a project with no C++ enabled.
set(bin ${work}/c-cmake-static)
hmc_run("find_package C consumer (static): configure"
        ${CMAKE_COMMAND} -S ${HMC_CONSUMER_SOURCE}/cmake_c -B ${bin} -G ${HMC_GENERATOR}
        -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=${HMC_C_COMPILER}
        -DCMAKE_PREFIX_PATH=${prefix} -Dhmc_USE_STATIC_LIBS=ON
        "-DCMAKE_C_FLAGS=${HMC_CONSUMER_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${HMC_CONSUMER_FLAGS}")
if(NOT flags)  # sanitized builds need the C++ driver to link (see 5.)
  hmc_run("find_package C consumer (static): build" ${CMAKE_COMMAND} --build ${bin})
  hmc_run("find_package C consumer (static): run" ${bin}/consumer_c ${stream})
  hmc_expect("consumer_c" "${HMC_OUT}" "consumer_c: 3 levels, libhmc ${HMC_VERSION}; streamed and whole decoding agree")
  hmc_check_needs("consumer_c (find_package, static)" ${bin}/consumer_c FALSE)
endif()

# 5. C through pkg-config.
if(NOT HMC_PKG_CONFIG)
  message(WARNING "pkg-config not found: the pkg-config consumer is not tested")
  return()
endif()
set(ENV{PKG_CONFIG_PATH} ${libdir}/pkgconfig)
hmc_run("pkg-config --modversion" ${HMC_PKG_CONFIG} --modversion hmc)
string(STRIP "${HMC_OUT}" version)
if(NOT version STREQUAL HMC_VERSION)
  message(FATAL_ERROR "pkg-config says hmc ${version}, expected ${HMC_VERSION}")
endif()
hmc_run("pkg-config --cflags" ${HMC_PKG_CONFIG} --cflags hmc)
separate_arguments(cflags UNIX_COMMAND "${HMC_OUT}")
hmc_run("pkg-config --libs" ${HMC_PKG_CONFIG} --libs hmc)
separate_arguments(libs UNIX_COMMAND "${HMC_OUT}")
hmc_run("pkg-config --libs --static" ${HMC_PKG_CONFIG} --libs --static hmc)
separate_arguments(static_libs UNIX_COMMAND "${HMC_OUT}")
hmc_run("pkg-config --variable=libdir" ${HMC_PKG_CONFIG} --variable=libdir hmc)
string(STRIP "${HMC_OUT}" pc_libdir)
# The static build: the same flags, libhmc.a named instead of -lhmc (which
# the linker would resolve to the shared library beside it).
list(TRANSFORM static_libs REPLACE "^-lhmc$" "-l:libhmc.a")

# Sanitized builds: the library's sanitizer runtime comes with the C++
# driver, so link with it (compiling stays plain C).
set(linker ${HMC_C_COMPILER})
if(flags)
  set(linker ${HMC_CXX_COMPILER})
endif()
set(src ${HMC_CONSUMER_SOURCE}/pkgconfig/main.c)
hmc_run("pkg-config consumer: compile" ${HMC_C_COMPILER} -std=c99 -Wall -Wextra -Wpedantic -Werror ${flags}
        ${cflags} -c ${src} -o ${work}/consumer_c.o)
set(kinds static)
if(HMC_SHARED)
  set(kinds shared static)
  hmc_run("pkg-config consumer (shared): link" ${linker} ${flags} ${work}/consumer_c.o -o ${work}/consumer_c_shared
          ${libs} -Wl,-rpath,${pc_libdir})
  hmc_check_needs("consumer_c (shared)" ${work}/consumer_c_shared TRUE)
endif()
hmc_run("pkg-config consumer (static): link" ${linker} ${flags} ${work}/consumer_c.o -o ${work}/consumer_c_static
        ${static_libs})
hmc_check_needs("consumer_c (static)" ${work}/consumer_c_static FALSE)
foreach(kind ${kinds})
  hmc_run("pkg-config consumer (${kind}): run" ${work}/consumer_c_${kind} ${stream})
  hmc_expect("consumer_c" "${HMC_OUT}" "consumer_c: 3 levels, libhmc ${HMC_VERSION}; streamed and whole decoding agree")
  message(STATUS "${HMC_OUT}")
endforeach()
