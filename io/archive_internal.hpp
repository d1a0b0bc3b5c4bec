// Internals shared by the run archive's files (io/archive.cpp: records and limits;
// archive_writer.cpp and its parts in archive_writer_internal.hpp: the writer;
// archive_reader.cpp: the reader; archive_digest.cpp: the digests). Not for use outside io/.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/archive.hpp"

namespace softevo::io::detail {

// Runs `body`; any other error (h5::Error, file system) is rethrown as an ArchiveError with the
// same message, so callers catch one type.
template <typename Body>
auto archive_errors(Body&& body) -> decltype(body()) {
  try {
    return body();
  } catch (const ArchiveError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw ArchiveError(e.what());
  }
}

// The longest string attribute a reader accepts (docs/archive.md "Limits").
constexpr auto kStringBytes = static_cast<std::size_t>(ArchiveLimits::string_bytes);

// The attribute "columns" of a components dataset: the names joined by commas.
constexpr const char* kColumnsAttribute = "columns";
std::string join_columns(const std::vector<std::string>& columns);
std::vector<std::string> split_columns(const std::string& text);

}  // namespace softevo::io::detail
