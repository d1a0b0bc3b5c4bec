# CMake toolchain: cross-compile softevo's core (common, physics, evo, worker and their tests) for
# AArch64 Linux with Debian's g++-aarch64-linux-gnu; the tests run under qemu-user. Used by
# `tools/bootstrap.sh aarch64`, which also builds GoogleTest for AArch64 and passes its GTest_DIR.
# MPI, HDF5 and libpng are not looked for (the core needs none of them).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# Libraries and headers only from the AArch64 tree (libc6-arm64-cross), programs from the host.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Test executables (also gtest_discover_tests' listing at build time) run under user-mode qemu with
# the AArch64 loader and libraries.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64-static;-L;/usr/aarch64-linux-gnu)

# The header-only libraries come from the host's Debian packages, which install for the host
# architecture only: Eigen's own package config (it points at /usr/include/eigen3), and for toml++
# and nlohmann-json the configs in cmake/cross/, which expose their headers alone (their Debian
# configs add all of /usr/include, whose C library headers are the host's, or toml++'s x86-64
# shared library).
set(Eigen3_DIR /usr/share/eigen3/cmake CACHE PATH "Eigen's package config (host, header-only)")
set(tomlplusplus_DIR ${CMAKE_CURRENT_LIST_DIR}/cross/tomlplusplus CACHE PATH "header-only toml++")
set(nlohmann_json_DIR ${CMAKE_CURRENT_LIST_DIR}/cross/nlohmann_json CACHE PATH "nlohmann-json")
set(CMAKE_DISABLE_FIND_PACKAGE_MPI ON CACHE BOOL "no AArch64 MPI in the cross build")
set(CMAKE_DISABLE_FIND_PACKAGE_HDF5 ON CACHE BOOL "no AArch64 HDF5 in the cross build")
set(CMAKE_DISABLE_FIND_PACKAGE_PNG ON CACHE BOOL "no AArch64 libpng in the cross build")
set(CMAKE_DISABLE_FIND_PACKAGE_GIF ON CACHE BOOL "no AArch64 giflib in the cross build")
