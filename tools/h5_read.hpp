// Small read-only HDF5 helpers for the CLI tools that inspect run archives and traces
// (`replay`, `render`). Every failure is a std::runtime_error naming the file, the object and
// the reason; the HDF5 library's own error printing is switched off.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <H5Cpp.h>

namespace softevo::h5read {

// Opens read-only; throws naming the path when it is missing or not HDF5.
H5::H5File open_file(const std::string& path);

bool has_attribute(const H5::H5Object& object, const std::string& name);
bool has_link(const H5::Group& group, const std::string& path);  // "a/b" nested allowed

// Attributes: strings may be fixed-length or variable-length; numbers any integer/float type.
std::string string_attribute(const H5::H5Object& object, const std::string& name,
                             const std::string& where);
double double_attribute(const H5::H5Object& object, const std::string& name,
                        const std::string& where);
std::int64_t int_attribute(const H5::H5Object& object, const std::string& name,
                           const std::string& where);

// A numeric dataset read in full, converted by HDF5 to the requested type; `dims` receives the
// shape. `where` names the file in messages.
std::vector<double> doubles(const H5::Group& group, const std::string& name,
                            std::vector<hsize_t>& dims, const std::string& where);
std::vector<std::int64_t> ints(const H5::Group& group, const std::string& name,
                               std::vector<hsize_t>& dims, const std::string& where);
// A scalar (or 1-element) string dataset, fixed- or variable-length.
std::string string_dataset(const H5::Group& group, const std::string& name,
                           const std::string& where);
// A 1-D dataset of variable-length uint8 sequences (archived genomes).
std::vector<std::vector<std::uint8_t>> byte_rows(const H5::Group& group, const std::string& name,
                                                 const std::string& where);

}  // namespace softevo::h5read
