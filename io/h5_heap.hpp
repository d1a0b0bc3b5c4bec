// The variable-length data of an HDF5 file, checked against the file's own bytes before libhdf5
// trusts it (docs/archive.md, "Limits"): the global heap collections that variable-length strings
// and sequences point into. Internal to io/ (h5.cpp reads through it).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/h5.hpp"

namespace softevo::io::h5 {

// The reason of a value or row longer than its read limit.
inline std::string too_long(std::uint64_t bytes, std::uint64_t max_bytes) {
  return "is " + std::to_string(bytes) + " bytes long, more than the limit of " +
         std::to_string(max_bytes) + " bytes";
}

// Before libhdf5 reads a variable-length attribute of `object`: every global heap collection of
// its file is well formed (h5::Error naming `action` otherwise).
void check_heaps_before_library_read(hid_t object, const Where& where, const std::string& action);

// The `rows` variable-length rows of a contiguous dataset, each checked against the global heap
// and at most `max_row_bytes` long.
std::vector<std::vector<std::uint8_t>> read_vlen_rows(hid_t dataset, const Where& where,
                                                      hsize_t rows, hsize_t max_row_bytes);

}  // namespace softevo::io::h5
