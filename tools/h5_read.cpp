#include "tools/h5_read.hpp"

#include <algorithm>
#include <functional>
#include <stdexcept>

namespace softevo::h5read {

namespace {

std::string detail(const H5::Exception& e) {
  const std::string d = e.getDetailMsg();
  return d.empty() ? std::string("HDF5 error") : d;
}

[[noreturn]] void fail(const std::string& where, const std::string& what,
                       const std::string& reason) {
  throw std::runtime_error(where + ": " + what + ": " + reason);
}

}  // namespace

H5::H5File open_file(const std::string& path) {
  H5::Exception::dontPrint();
  try {
    if (!H5::H5File::isHdf5(path)) fail(path, "file", "not an HDF5 file");
    return H5::H5File(path, H5F_ACC_RDONLY);
  } catch (const H5::Exception& e) {
    fail(path, "cannot open", detail(e));
  }
}

bool has_attribute(const H5::H5Object& object, const std::string& name) {
  return object.attrExists(name);
}

bool has_link(const H5::Group& group, const std::string& path) {
  // Check each level: H5Lexists on "a/b" fails when "a" is missing.
  std::string prefix;
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t slash = path.find('/', start);
    const std::string part =
        path.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (!part.empty()) {
      prefix += (prefix.empty() ? "" : "/") + part;
      if (H5Lexists(group.getId(), prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    }
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  return true;
}

namespace {

std::string read_string(const H5::DataType& type, const H5::DataSpace& space,
                        const std::function<void(const H5::DataType&, void*)>& read,
                        const std::string& where, const std::string& what) {
  if (type.getClass() != H5T_STRING) fail(where, what, "is not a string");
  if (space.getSimpleExtentNpoints() != 1) fail(where, what, "is not a single string");
  H5::StrType file_type = H5::StrType(type.getId());
  // HDF5 refuses to convert between character sets, so read in the file's own (the run archive
  // writes UTF-8, traces ASCII).
  H5::StrType str_type(H5::PredType::C_S1, H5T_VARIABLE);
  str_type.setCset(file_type.getCset());
  if (file_type.isVariableStr()) {
    char* buffer = nullptr;
    read(str_type, &buffer);
    std::string value = buffer ? std::string(buffer) : std::string();
    H5::DataSet::vlenReclaim(&buffer, str_type, space);
    return value;
  }
  const std::size_t size = type.getSize();
  std::string value(size, '\0');
  H5::StrType fixed(H5::PredType::C_S1, size);
  fixed.setCset(file_type.getCset());
  read(fixed, value.data());
  const std::size_t end = value.find('\0');
  if (end != std::string::npos) value.resize(end);
  return value;
}

}  // namespace

std::string string_attribute(const H5::H5Object& object, const std::string& name,
                             const std::string& where) {
  try {
    if (!object.attrExists(name)) fail(where, "attribute '" + name + "'", "missing");
    const H5::Attribute attr = object.openAttribute(name);
    return read_string(
        attr.getDataType(), attr.getSpace(),
        [&attr](const H5::DataType& t, void* buf) { attr.read(t, buf); }, where,
        "attribute '" + name + "'");
  } catch (const H5::Exception& e) {
    fail(where, "attribute '" + name + "'", detail(e));
  }
}

double double_attribute(const H5::H5Object& object, const std::string& name,
                        const std::string& where) {
  try {
    if (!object.attrExists(name)) fail(where, "attribute '" + name + "'", "missing");
    const H5::Attribute attr = object.openAttribute(name);
    const H5T_class_t cls = attr.getDataType().getClass();
    if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
      fail(where, "attribute '" + name + "'", "is not a number");
    }
    if (attr.getSpace().getSimpleExtentNpoints() != 1) {
      fail(where, "attribute '" + name + "'", "is not a single number");
    }
    double value = 0.0;
    attr.read(H5::PredType::NATIVE_DOUBLE, &value);
    return value;
  } catch (const H5::Exception& e) {
    fail(where, "attribute '" + name + "'", detail(e));
  }
}

std::int64_t int_attribute(const H5::H5Object& object, const std::string& name,
                           const std::string& where) {
  try {
    if (!object.attrExists(name)) fail(where, "attribute '" + name + "'", "missing");
    const H5::Attribute attr = object.openAttribute(name);
    if (attr.getDataType().getClass() != H5T_INTEGER) {
      fail(where, "attribute '" + name + "'", "is not an integer");
    }
    if (attr.getSpace().getSimpleExtentNpoints() != 1) {
      fail(where, "attribute '" + name + "'", "is not a single integer");
    }
    std::int64_t value = 0;
    attr.read(H5::PredType::NATIVE_INT64, &value);
    return value;
  } catch (const H5::Exception& e) {
    fail(where, "attribute '" + name + "'", detail(e));
  }
}

namespace {

template <typename T>
std::vector<T> read_numeric(const H5::Group& group, const std::string& name,
                            std::vector<hsize_t>& dims, const std::string& where,
                            const H5::PredType& mem_type) {
  try {
    if (!has_link(group, name)) fail(where, "dataset '" + name + "'", "missing");
    const H5::DataSet ds = group.openDataSet(name);
    const H5T_class_t cls = ds.getDataType().getClass();
    if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
      fail(where, "dataset '" + name + "'", "is not numeric");
    }
    const H5::DataSpace space = ds.getSpace();
    const int rank = space.getSimpleExtentNdims();
    dims.assign(static_cast<std::size_t>(std::max(rank, 0)), 0);
    if (rank > 0) space.getSimpleExtentDims(dims.data());
    std::vector<T> values(static_cast<std::size_t>(space.getSimpleExtentNpoints()));
    if (!values.empty()) ds.read(values.data(), mem_type);
    return values;
  } catch (const H5::Exception& e) {
    fail(where, "dataset '" + name + "'", detail(e));
  }
}

}  // namespace

std::vector<double> doubles(const H5::Group& group, const std::string& name,
                            std::vector<hsize_t>& dims, const std::string& where) {
  return read_numeric<double>(group, name, dims, where, H5::PredType::NATIVE_DOUBLE);
}

std::vector<std::int64_t> ints(const H5::Group& group, const std::string& name,
                               std::vector<hsize_t>& dims, const std::string& where) {
  return read_numeric<std::int64_t>(group, name, dims, where, H5::PredType::NATIVE_INT64);
}

std::string string_dataset(const H5::Group& group, const std::string& name,
                           const std::string& where) {
  try {
    if (!has_link(group, name)) fail(where, "dataset '" + name + "'", "missing");
    const H5::DataSet ds = group.openDataSet(name);
    return read_string(
        ds.getDataType(), ds.getSpace(),
        [&ds](const H5::DataType& t, void* buf) { ds.read(buf, t); }, where,
        "dataset '" + name + "'");
  } catch (const H5::Exception& e) {
    fail(where, "dataset '" + name + "'", detail(e));
  }
}

std::vector<std::vector<std::uint8_t>> byte_rows(const H5::Group& group, const std::string& name,
                                                 const std::string& where) {
  try {
    if (!has_link(group, name)) fail(where, "dataset '" + name + "'", "missing");
    const H5::DataSet ds = group.openDataSet(name);
    if (ds.getDataType().getClass() != H5T_VLEN) {
      fail(where, "dataset '" + name + "'", "is not a variable-length byte column");
    }
    const H5::DataSpace space = ds.getSpace();
    const auto n = static_cast<std::size_t>(space.getSimpleExtentNpoints());
    const H5::VarLenType mem_type(H5::PredType::NATIVE_UINT8);
    std::vector<hvl_t> raw(n);
    if (n > 0) ds.read(raw.data(), mem_type);
    std::vector<std::vector<std::uint8_t>> rows(n);
    for (std::size_t i = 0; i < n; ++i) {
      const auto* p = static_cast<const std::uint8_t*>(raw[i].p);
      rows[i].assign(p, p + raw[i].len);
    }
    if (n > 0) H5::DataSet::vlenReclaim(raw.data(), mem_type, space);
    return rows;
  } catch (const H5::Exception& e) {
    fail(where, "dataset '" + name + "'", detail(e));
  }
}

}  // namespace softevo::h5read
