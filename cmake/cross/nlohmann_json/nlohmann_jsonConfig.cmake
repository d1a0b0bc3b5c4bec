# nlohmann-json (header-only) for the cross build: Debian's config adds all of /usr/include.
include(${CMAKE_CURRENT_LIST_DIR}/../header_only.cmake)
softevo_cross_header_library(TARGET nlohmann_json::nlohmann_json HEADERS nlohmann)
