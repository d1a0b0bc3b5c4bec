# toml++ header-only (TOML_HEADER_ONLY=1) for the cross build: Debian's config links its host
# shared library. Same parser, compiled into the one translation unit that includes it.
include(${CMAKE_CURRENT_LIST_DIR}/../header_only.cmake)
softevo_cross_header_library(TARGET tomlplusplus::tomlplusplus HEADERS toml++
                             DEFINITIONS TOML_HEADER_ONLY=1)
set(tomlplusplus_VERSION 3.3.0)
