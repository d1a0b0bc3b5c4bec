# Dependencies, each required only by the targets that use it.
#
# Optional parts follow one pattern: SOFTEVO_REQUIRE_<X> (default OFF) turns "not found" into a
# configure error; SOFTEVO_ENABLE_<X> records what was found and decides what gets built.
#   TESTS  GoogleTest             the test suite
#   PNG    libpng                 `softevo render` to .png (without it: .mp4 only, via ffmpeg)
#   GIF    giflib                 `softevo render` to an animated .gif
#   3MF    lib3mf 1.x             `softevo fabricate` to .3mf and `fabricate --check`
#   MPI    MPI (C++ bindings off) softevo-mpi and the MPI tests
#   HDF5   HDF5 C                 io (run archive, trace), the master, softevo-mpi, the softevo CLI
#   PYTHON Python 3 + pybind11    the `softevo` Python package (python/; also needs HDF5)
# The core (common, physics, evo, worker and their tests) needs none of them, only the
# header-only libraries below.
#
# Header-only libraries (Eigen, CLI11, nlohmann-json, toml++) are looked up with find_package;
# with SOFTEVO_FETCH_MISSING a missing one is downloaded at configure time from a pinned URL
# checked by SHA256, so a cluster with only a compiler, CMake, MPI and HDF5 can build softevo-mpi.

option(SOFTEVO_FETCH_MISSING
       "download missing header-only libraries (Eigen, CLI11, nlohmann-json) at configure time" ON)
option(SOFTEVO_REQUIRE_TESTS "fail at configure time unless GoogleTest is found" OFF)
option(SOFTEVO_REQUIRE_PNG "fail at configure time unless libpng is found" OFF)
option(SOFTEVO_REQUIRE_GIF "fail at configure time unless giflib is found" OFF)
option(SOFTEVO_REQUIRE_3MF "fail at configure time unless lib3mf (1.x C interface) is found" OFF)
option(SOFTEVO_REQUIRE_MPI "fail at configure time unless MPI is found" OFF)
option(SOFTEVO_REQUIRE_HDF5 "fail at configure time unless HDF5 (C) is found" OFF)
option(SOFTEVO_REQUIRE_PYTHON
       "fail at configure time unless Python 3 (headers) and pybind11 are found" OFF)
option(SOFTEVO_REQUIRE_VIEW
       "fail at configure time unless Boost.Beast and zlib (`softevo view`) are found" OFF)

include(FetchContent)

# softevo_optional(NAME X FOUND var HOW "install hint")
#   after the find_package call: sets SOFTEVO_ENABLE_X from `var`, fails if SOFTEVO_REQUIRE_X.
macro(softevo_optional)
  cmake_parse_arguments(_opt "" "NAME;FOUND;HOW" "" ${ARGN})
  if(${_opt_FOUND})
    set(SOFTEVO_ENABLE_${_opt_NAME} ON)
  else()
    set(SOFTEVO_ENABLE_${_opt_NAME} OFF)
    if(SOFTEVO_REQUIRE_${_opt_NAME})
      message(FATAL_ERROR
        "SOFTEVO_REQUIRE_${_opt_NAME} is ON but ${_opt_NAME} was not found: ${_opt_HOW}")
    endif()
  endif()
endmacro()

find_package(GTest QUIET)
softevo_optional(NAME TESTS FOUND GTest_FOUND HOW "install libgtest-dev (Debian) or set GTest_DIR")

find_package(PNG QUIET)
softevo_optional(NAME PNG FOUND PNG_FOUND HOW "install libpng-dev (Debian) or set PNG_ROOT")

find_package(GIF 5 QUIET)
softevo_optional(NAME GIF FOUND GIF_FOUND HOW "install libgif-dev (Debian) or set GIF_DIR")

# lib3mf 1.x (Debian lib3mf-dev): its C interface header and library, as an imported target.
find_path(SOFTEVO_LIB3MF_INCLUDE_DIR Model/COM/NMR_DLLInterfaces.h PATH_SUFFIXES lib3mf)
find_library(SOFTEVO_LIB3MF_LIBRARY 3MF)
if(SOFTEVO_LIB3MF_INCLUDE_DIR AND SOFTEVO_LIB3MF_LIBRARY)
  set(softevo_lib3mf_found ON)
  add_library(softevo::lib3mf UNKNOWN IMPORTED)
  set_target_properties(softevo::lib3mf PROPERTIES IMPORTED_LOCATION ${SOFTEVO_LIB3MF_LIBRARY})
  target_include_directories(softevo::lib3mf SYSTEM INTERFACE ${SOFTEVO_LIB3MF_INCLUDE_DIR})
else()
  set(softevo_lib3mf_found OFF)
endif()
softevo_optional(NAME 3MF FOUND softevo_lib3mf_found HOW "install lib3mf-dev (Debian)")

find_package(MPI QUIET COMPONENTS CXX)
softevo_optional(NAME MPI FOUND MPI_FOUND
                 HOW "install libopenmpi-dev (Debian), or load your cluster's MPI module")

# The C library only (io/h5.hpp): clusters often install HDF5 without the C++ bindings.
find_package(HDF5 QUIET COMPONENTS C)
softevo_optional(NAME HDF5 FOUND HDF5_FOUND
                 HOW "install libhdf5-dev (Debian), or load your cluster's HDF5 module")

# The Python package is built for Debian's interpreter (/usr/bin/python3, where python3-numpy,
# -pandas and -pytest live) even when another python3 comes first on PATH (pyenv, conda);
# -DPython_EXECUTABLE=... chooses another. It binds the run archive reader, so it needs HDF5.
if(NOT DEFINED Python_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter of the softevo package")
endif()
if(SOFTEVO_ENABLE_HDF5)
  find_package(Python 3.9 QUIET COMPONENTS Interpreter Development.Module)
endif()
if(Python_FOUND)
  find_package(pybind11 2.6 CONFIG QUIET)
endif()
if(Python_FOUND AND pybind11_FOUND AND SOFTEVO_ENABLE_HDF5)
  set(softevo_python_found ON)
else()
  set(softevo_python_found OFF)
endif()
softevo_optional(NAME PYTHON FOUND softevo_python_found
                 HOW "install python3-dev and pybind11-dev (Debian); the package also needs HDF5")

# softevo_header_library(PACKAGE P TARGET T DEBIAN deb [MINIMUM v] [FIND_ARGS ...]
#                        [VERSION v URLS u ... SHA256 h INCLUDE_DIR dir [DEBIAN_PACKAGE_FILE]])
#   find_package(P MINIMUM); when missing and a pinned download is known, fetch it and define the
#   INTERFACE target T over its headers (no build of the project's own CMake: we need headers
#   only). DEBIAN_PACKAGE_FILE: the download is a Debian binary package (.deb), whose data
#   archive holds the headers. Records how it was satisfied in SOFTEVO_SOURCE_<P> for the
#   summary.
function(softevo_header_library)
  cmake_parse_arguments(H "DEBIAN_PACKAGE_FILE" "PACKAGE;TARGET;DEBIAN;MINIMUM;VERSION;SHA256;INCLUDE_DIR"
                        "FIND_ARGS;URLS" ${ARGN})
  find_package(${H_PACKAGE} ${H_MINIMUM} QUIET ${H_FIND_ARGS})
  if(${H_PACKAGE}_FOUND AND TARGET ${H_TARGET})
    set(SOFTEVO_SOURCE_${H_PACKAGE} "found ${${H_PACKAGE}_VERSION}" PARENT_SCOPE)
    return()
  endif()
  set(how "install ${H_DEBIAN} (Debian) or point CMAKE_PREFIX_PATH at an install of it")
  if(NOT H_URLS)
    message(FATAL_ERROR "${H_PACKAGE} not found and softevo knows no checked download of it: ${how}")
  endif()
  if(NOT SOFTEVO_FETCH_MISSING)
    message(FATAL_ERROR "${H_PACKAGE} not found and SOFTEVO_FETCH_MISSING is OFF: ${how}, "
                        "or configure with -DSOFTEVO_FETCH_MISSING=ON to download it")
  endif()
  string(TOLOWER "softevo_dep_${H_PACKAGE}" content)
  if(H_DEBIAN_PACKAGE_FILE)
    # A Debian binary package (an ar archive): its headers are in data.tar.xz.
    set(root ${CMAKE_BINARY_DIR}/_deps/${content})
    if(NOT EXISTS ${root}/${H_INCLUDE_DIR})
      message(STATUS "${H_PACKAGE} not found: downloading ${H_VERSION} (SOFTEVO_FETCH_MISSING)")
      set(fetched OFF)
      foreach(url ${H_URLS})
        file(DOWNLOAD ${url} ${root}/package.deb EXPECTED_HASH SHA256=${H_SHA256} STATUS status)
        list(GET status 0 code)
        if(code EQUAL 0)
          set(fetched ON)
          break()
        endif()
      endforeach()
      if(NOT fetched)
        message(FATAL_ERROR "${H_PACKAGE}: no download matched its SHA256 (${status}): ${how}")
      endif()
      file(ARCHIVE_EXTRACT INPUT ${root}/package.deb DESTINATION ${root}/package)
      file(ARCHIVE_EXTRACT INPUT ${root}/package/data.tar.xz DESTINATION ${root})
    endif()
    set(include_root ${root})
  else()
    FetchContent_Declare(${content} URL ${H_URLS} URL_HASH SHA256=${H_SHA256})
    FetchContent_GetProperties(${content})
    if(NOT ${content}_POPULATED)
      message(STATUS "${H_PACKAGE} not found: downloading ${H_VERSION} (SOFTEVO_FETCH_MISSING)")
      FetchContent_Populate(${content})
    endif()
    set(include_root ${${content}_SOURCE_DIR})
  endif()
  add_library(${H_TARGET} INTERFACE IMPORTED GLOBAL)
  target_include_directories(${H_TARGET} INTERFACE ${include_root}/${H_INCLUDE_DIR})
  set(SOFTEVO_SOURCE_${H_PACKAGE} "downloaded ${H_VERSION}" PARENT_SCOPE)
endfunction()

# Pinned to the versions Debian 12 ships. The SHA256 sums are those of Debian's source tarballs
# (checked against the packages' .dsc files); the Eigen and nlohmann-json tarballs are the
# upstream release tarballs unchanged, so the upstream URLs serve as fallbacks.
set(SOFTEVO_DEBIAN_POOL "http://deb.debian.org/debian/pool/main")
softevo_header_library(PACKAGE Eigen3 MINIMUM 3.3 VERSION 3.4.0 TARGET Eigen3::Eigen DEBIAN libeigen3-dev
  FIND_ARGS NO_MODULE
  URLS ${SOFTEVO_DEBIAN_POOL}/e/eigen3/eigen3_3.4.0.orig.tar.bz2
       https://gitlab.com/libeigen/eigen/-/archive/3.4.0/eigen-3.4.0.tar.bz2
  SHA256 b4c198460eba6f28d34894e3a5710998818515104d6e74e5cc331ce31e46e626
  INCLUDE_DIR .)
softevo_header_library(PACKAGE nlohmann_json MINIMUM 3 VERSION 3.11.2 TARGET nlohmann_json::nlohmann_json
  DEBIAN nlohmann-json3-dev
  URLS ${SOFTEVO_DEBIAN_POOL}/n/nlohmann-json3/nlohmann-json3_3.11.2.orig.tar.gz
       https://github.com/nlohmann/json/archive/refs/tags/v3.11.2.tar.gz
  SHA256 d69f9deb6a75e2580465c6c4c5111b89c4dc2fa94e3a85fcd2ffcd9a143d9273
  INCLUDE_DIR include)
# toml++: the Debian mirror serves no source tarball of 3.3.0+ds, so the headers come from the
# binary package libtomlplusplus-dev (its sum is the one in Debian 12's Packages index). Its
# headers are architecture-independent; without Debian's shared library they compile in toml++'s
# header-only mode, the same parser.
softevo_header_library(PACKAGE tomlplusplus VERSION 3.3.0 TARGET tomlplusplus::tomlplusplus
  DEBIAN libtomlplusplus-dev DEBIAN_PACKAGE_FILE
  URLS ${SOFTEVO_DEBIAN_POOL}/t/tomlplusplus/libtomlplusplus-dev_3.3.0%2bds-1_amd64.deb
  SHA256 2779cce0001466dcf60eb6262ff68a888d49f9e30aee80c499d1d4f6f9f6e12e
  INCLUDE_DIR usr/include)

# CLI11 only serves the executables (softevo, softevo-mpi), which need HDF5.
if(SOFTEVO_ENABLE_HDF5)
  # Debian's tarball is repacked (+ds: generated files removed), so no upstream fallback.
  softevo_header_library(PACKAGE CLI11 VERSION 2.1.2 TARGET CLI11::CLI11 DEBIAN libcli11-dev
    URLS ${SOFTEVO_DEBIAN_POOL}/c/cli11/cli11_2.1.2+ds.orig.tar.xz
    SHA256 8143d20b688e98ccce8e24562d3b68e5f47c12e896c42c7ca8553dbde5bed55d
    INCLUDE_DIR include)
endif()

# What gets built, from what was found.
set(SOFTEVO_BUILD_MASTER ${SOFTEVO_ENABLE_HDF5})
if(SOFTEVO_ENABLE_HDF5 AND SOFTEVO_ENABLE_MPI)
  set(SOFTEVO_BUILD_SOFTEVO_MPI ON)
else()
  set(SOFTEVO_BUILD_SOFTEVO_MPI OFF)
endif()
set(SOFTEVO_BUILD_CLI ${SOFTEVO_ENABLE_HDF5})

# `softevo view` (view/): Boost.Beast (header-only, in Boost's headers) for HTTP and WebSocket,
# zlib for the exported page's frames; part of the CLI, so it needs HDF5 too.
find_package(Boost 1.70 QUIET)
find_package(ZLIB QUIET)
if(Boost_FOUND AND ZLIB_FOUND AND SOFTEVO_BUILD_CLI AND EXISTS "${Boost_INCLUDE_DIRS}/boost/beast.hpp")
  set(softevo_view_found ON)
else()
  set(softevo_view_found OFF)
endif()
softevo_optional(NAME VIEW FOUND softevo_view_found
                 HOW "install libboost-dev and zlib1g-dev (Debian); the viewer also needs HDF5")

function(softevo_print_summary)
  set(built "common physics evo worker render")
  if(SOFTEVO_ENABLE_MPI)
    string(APPEND built " worker_mpi")
  endif()
  if(SOFTEVO_ENABLE_HDF5)
    string(APPEND built " io motion")
  endif()
  if(SOFTEVO_BUILD_MASTER)
    string(APPEND built " master")
  endif()
  if(SOFTEVO_BUILD_SOFTEVO_MPI)
    string(APPEND built " master_mpi softevo-mpi")
  endif()
  if(SOFTEVO_BUILD_CLI)
    string(APPEND built " softevo")
    set(formats "")
    if(SOFTEVO_ENABLE_PNG)
      string(APPEND formats " .png")
    endif()
    if(SOFTEVO_ENABLE_GIF)
      string(APPEND formats " .gif")
    endif()
    string(APPEND built "(render${formats} .mp4)")
  endif()
  if(SOFTEVO_ENABLE_VIEW)
    string(APPEND built " view")
  endif()
  if(SOFTEVO_ENABLE_PYTHON)
    string(APPEND built " python")
  endif()
  if(SOFTEVO_ENABLE_TESTS)
    string(APPEND built " tests")
  endif()
  message(STATUS "softevo configuration:")
  message(STATUS "  GoogleTest    ${SOFTEVO_ENABLE_TESTS}")
  message(STATUS "  libpng        ${SOFTEVO_ENABLE_PNG}")
  message(STATUS "  giflib        ${SOFTEVO_ENABLE_GIF}")
  message(STATUS "  lib3mf        ${SOFTEVO_ENABLE_3MF}")
  message(STATUS "  MPI           ${SOFTEVO_ENABLE_MPI}")
  message(STATUS "  HDF5 C        ${SOFTEVO_ENABLE_HDF5}")
  message(STATUS "  viewer        ${SOFTEVO_ENABLE_VIEW} (Boost.Beast, zlib)")
  if(SOFTEVO_ENABLE_PYTHON)
    message(STATUS "  Python        ${Python_EXECUTABLE} ${Python_VERSION}, pybind11 ${pybind11_VERSION}")
  else()
    message(STATUS "  Python        OFF")
  endif()
  foreach(p Eigen3 tomlplusplus nlohmann_json CLI11)
    if(DEFINED SOFTEVO_SOURCE_${p})
      string(SUBSTRING "${p}              " 0 14 label)
      message(STATUS "  ${label}${SOFTEVO_SOURCE_${p}}")
    endif()
  endforeach()
  message(STATUS "  builds        ${built}")
endfunction()
