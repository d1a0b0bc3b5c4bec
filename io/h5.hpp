// A thin RAII layer over the HDF5 C API, shared by the run archive and the trace (the C++
// bindings are not used: many clusters install HDF5 without them).
//
// Every handle (file, group, dataset, dataspace, attribute, datatype, property list) closes
// itself when destroyed. Every failing HDF5 call becomes an h5::Error that names the file, the
// object path inside it, what was attempted and the reason HDF5 gave; HDF5's own printing of
// its error stack to stderr is switched off and the stack is turned into that reason instead.
//
// This header includes <hdf5.h>; only io/ and its tests include it (the module rule of
// tests/common/test_module_rules.cpp). Other rooms use io/archive.hpp and io/trace.hpp.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace softevo::io::h5 {

// A failed HDF5 operation. what() = "<file>: <object>: <action>: <reason>".
class Error : public std::runtime_error {
 public:
  Error(std::string file, std::string object, std::string action, std::string reason);
  const std::string& file() const { return file_; }
  const std::string& object() const { return object_; }  // path inside the file, "/" = root
  const std::string& action() const { return action_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, object_, action_, reason_;
};

// A file the structure probe refused (io/open_probe.hpp): libhdf5 crashed or hung on it in a
// test process. Callers that only ask "is this my kind of file?" let it through: "damaged" is
// the answer the user needs, not "not an archive".
class DamagedFileError : public Error {
 public:
  using Error::Error;
};

// Read limits. Every read is bounded before anything is allocated: a dataset never yields more
// values than its file has bytes for (a flipped extent or length would otherwise make HDF5
// allocate and fill gigabytes), and each caller passes the tighter limit its schema allows
// (docs/archive.md, docs/trace.md "Limits"). kUnbounded = only the file's own size bounds it.
inline constexpr hsize_t kUnbounded = std::numeric_limits<hsize_t>::max();
// Strings read without an explicit limit (schema strings pass their own).
inline constexpr std::size_t kDefaultMaxStringBytes = std::size_t{16} << 20;

// Switches HDF5's automatic error printing off for the process (idempotent). Every entry of
// this layer calls it, so callers need not.
void silence_error_printing();
// The most specific message on HDF5's current error stack, and clears the stack; "" when the
// stack is empty.
std::string take_error_message();

// Owns one hid_t and closes it with its close function.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& other) noexcept : id_(std::exchange(other.id_, H5I_INVALID_HID)), close_(other.close_) {}
  Id& operator=(Id&& other) noexcept {
    if (this != &other) {
      reset();
      id_ = std::exchange(other.id_, H5I_INVALID_HID);
      close_ = other.close_;
    }
    return *this;
  }
  ~Id() { reset(); }
  void reset() {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Gives up ownership (the caller closes the id).
  hid_t release() { return std::exchange(id_, H5I_INVALID_HID); }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

// Memory and on-disk types of the numbers this project stores. The on-disk types are fixed
// little-endian, so a file is the same on every host; HDF5 converts on read and write.
template <typename T>
struct Number;
template <>
struct Number<std::uint8_t> {
  static hid_t memory() { return H5T_NATIVE_UINT8; }
  static hid_t file() { return H5T_STD_U8LE; }
};
template <>
struct Number<std::int32_t> {
  static hid_t memory() { return H5T_NATIVE_INT32; }
  static hid_t file() { return H5T_STD_I32LE; }
};
template <>
struct Number<std::int64_t> {
  static hid_t memory() { return H5T_NATIVE_INT64; }
  static hid_t file() { return H5T_STD_I64LE; }
};
template <>
struct Number<float> {
  static hid_t memory() { return H5T_NATIVE_FLOAT; }
  static hid_t file() { return H5T_IEEE_F32LE; }
};
template <>
struct Number<double> {
  static hid_t memory() { return H5T_NATIVE_DOUBLE; }
  static hid_t file() { return H5T_IEEE_F64LE; }
};

// Character set recorded with a string (HDF5 will not convert between the two, so a reader
// reads in the set the file has).
enum class Charset { ascii, utf8 };

// Names the file and the object for messages.
struct Where {
  std::string file;
  std::string object;  // "/", "/generations/000001", "/stats"
  // The path of a child: Where{f, "/a"}.child("b") = {f, "/a/b"}.
  Where child(const std::string& name) const;
  // Throws Error{file, object, action, reason}; reason "" = HDF5's current error message.
  [[noreturn]] void fail(const std::string& action, std::string reason = "") const;
  // Throws (as fail) when `id` < 0, else returns it.
  hid_t check(hid_t id, const std::string& action) const;
  void check_status(herr_t status, const std::string& action) const;
};

class Dataspace {
 public:
  static Dataspace scalar();
  // `max_dims` empty = fixed size; H5S_UNLIMITED entries let the dataset grow.
  static Dataspace simple(const std::vector<hsize_t>& dims,
                          const std::vector<hsize_t>& max_dims = {});
  Dataspace(Id id, Where where) : id_(std::move(id)), where_(std::move(where)) {}
  hid_t id() const { return id_.get(); }
  // Simple extent; {} for a scalar space.
  std::vector<hsize_t> dims() const;
  hsize_t points() const;
  // Selects the block [start, start + count) (one block per axis).
  void select_block(const std::vector<hsize_t>& start, const std::vector<hsize_t>& count);

 private:
  Id id_;
  Where where_;
};

// Creation properties: files and datasets.
class PropertyList {
 public:
  static PropertyList file_creation();
  static PropertyList dataset_creation();
  hid_t id() const { return id_.get(); }
  // Files: keep track of freed space across opens, so that space freed by replacing an object
  // is reused by the next write instead of growing the file (HDF5 >= 1.10.1).
  PropertyList& persist_free_space();
  // Datasets: chunked storage (required for a dataset that can grow).
  PropertyList& chunk(const std::vector<hsize_t>& chunk_dims);

 private:
  explicit PropertyList(Id id) : id_(std::move(id)) {}
  Id id_;
};

// A file, group or dataset: something that carries attributes.
class Object {
 public:
  hid_t id() const { return id_.get(); }
  const Where& where() const { return where_; }

  bool has_attribute(const std::string& name) const;
  // Attributes are written as scalars and replace an attribute of the same name.
  template <typename T>
  void write_attribute(const std::string& name, T value) const {
    write_attribute_raw(name, Number<T>::file(), Number<T>::memory(), &value);
  }
  void write_string_attribute(const std::string& name, const std::string& value,
                              Charset charset) const;
  // A scalar (or one-element) numeric attribute of any integer or float type, converted by HDF5
  // to T (an integer attribute when T is an integer type). Throws when missing.
  template <typename T>
  T read_attribute(const std::string& name) const {
    T value{};
    read_attribute_raw(name, Number<T>::memory(), std::is_integral_v<T>, &value);
    return value;
  }
  // A fixed- or variable-length string attribute of at most `max_bytes` bytes. Throws when
  // missing, not a string or longer.
  std::string read_string_attribute(const std::string& name,
                                    std::size_t max_bytes = kDefaultMaxStringBytes) const;

 protected:
  Object(Id id, Where where) : id_(std::move(id)), where_(std::move(where)) {}
  Id id_;
  Where where_;

 private:
  void write_attribute_raw(const std::string& name, hid_t file_type, hid_t memory_type,
                           const void* value) const;
  void read_attribute_raw(const std::string& name, hid_t memory_type, bool integer,
                          void* value) const;
};

class Dataset : public Object {
 public:
  Dataset(Id id, Where where) : Object(std::move(id), std::move(where)) {}
  Dataspace space() const;
  std::vector<hsize_t> dims() const { return space().dims(); }
  H5T_class_t type_class() const;

  // The whole dataset, converted by HDF5 to T; a float or integer dataset (integer only when T
  // is an integer type) of at most `max_points` values (checked before reading).
  template <typename T>
  std::vector<T> read(hsize_t max_points = kUnbounded) const {
    std::vector<T> values(static_cast<std::size_t>(checked_points(max_points)));
    read_raw(Number<T>::memory(), std::is_integral_v<T>, values.data(), values.size());
    return values;
  }
  // The number of values, after checking that the extent is at most `max_points` values and
  // fits in the bytes of the file that holds the dataset (a chunked dataset with a huge extent
  // and no chunks would otherwise be filled in memory with its fill value). Throws naming the
  // file, the dataset and the limit.
  hsize_t checked_points(hsize_t max_points = kUnbounded) const;
  // The whole dataset; `values` must have one element per point.
  template <typename T>
  void write(const std::vector<T>& values) const {
    write_raw(Number<T>::memory(), values.data(), values.size());
  }
  // Grows (or shrinks) a chunked dataset to `dims`.
  void set_extent(const std::vector<hsize_t>& dims) const;
  // Writes `values` (row-major, shape `count`) into the block at `start`.
  template <typename T>
  void write_block(const std::vector<hsize_t>& start, const std::vector<hsize_t>& count,
                   const std::vector<T>& values) const {
    write_block_raw(start, count, Number<T>::memory(), values.data(), values.size());
  }
  // A scalar (or one-element) string dataset, fixed- or variable-length, of at most `max_bytes`.
  std::string read_string(std::size_t max_bytes = kDefaultMaxStringBytes) const;
  // A 1-D dataset of variable-length uint8 sequences: at most `max_rows` rows of at most
  // `max_row_bytes` bytes each. Variable-length data is read from the file's bytes by this
  // layer, every reference and global heap object checked, not by libhdf5 (whose global heap
  // reader trusts the lengths it finds: a flipped byte there made it allocate gigabytes or
  // copy past its buffers).
  std::vector<std::vector<std::uint8_t>> read_byte_rows(hsize_t max_rows = kUnbounded,
                                                        hsize_t max_row_bytes = kUnbounded) const;

 private:
  void read_raw(hid_t memory_type, bool integer, void* out, std::size_t count) const;
  void write_raw(hid_t memory_type, const void* values, std::size_t count) const;
  void write_block_raw(const std::vector<hsize_t>& start, const std::vector<hsize_t>& count,
                       hid_t memory_type, const void* values, std::size_t value_count) const;
};

class Group : public Object {
 public:
  Group(Id id, Where where) : Object(std::move(id), std::move(where)) {}

  // A link named `path` exists; "a/b" is checked level by level (HDF5 itself fails when "a"
  // is missing).
  bool has_link(const std::string& path) const;
  void delete_link(const std::string& name) const;
  // Names of the direct children, in ascending name order; at most `max_links` of them (more
  // is an error naming the group and the limit).
  std::vector<std::string> link_names(hsize_t max_links = kUnbounded) const;

  // Where the external link `name` points: the object `object` in the file `file` (HDF5 resolves
  // a relative `file` against the directory of the file holding the link first). nullopt when
  // `name` is a hard or soft link.
  struct ExternalTarget {
    std::string file;
    std::string object;
  };
  std::optional<ExternalTarget> external_link(const std::string& name) const;
  void create_external_link(const std::string& name, const ExternalTarget& target) const;
  // Copies the object `name` (links followed) with its attributes and everything below it to
  // `destination_name` in `destination`, which may be in another file.
  void copy_object(const std::string& name, const Group& destination,
                   const std::string& destination_name) const;

  Group create_group(const std::string& name) const;
  Group open_group(const std::string& name) const;

  // An empty dataset of numbers with the given space (e.g. growable) and creation properties.
  template <typename T>
  Dataset create_dataset(const std::string& name, const Dataspace& space,
                         const PropertyList* creation = nullptr) const {
    return create_dataset_raw(name, Number<T>::file(), space, creation);
  }
  // A dataset of shape `dims` holding `values` (row-major, one value per point).
  template <typename T>
  Dataset write_dataset(const std::string& name, const std::vector<hsize_t>& dims,
                        const std::vector<T>& values) const {
    Dataset ds = create_dataset<T>(name, Dataspace::simple(dims));
    ds.write(values);
    return ds;
  }
  // A scalar variable-length string dataset.
  Dataset write_string_dataset(const std::string& name, const std::string& text,
                               Charset charset) const;
  // A 1-D dataset of variable-length uint8 sequences, one per row.
  Dataset write_byte_rows(const std::string& name,
                          const std::vector<std::vector<std::uint8_t>>& rows) const;

  Dataset open_dataset(const std::string& name) const;
  // open_dataset(name).read<T>(max_points), with its shape in `dims` when given.
  template <typename T>
  std::vector<T> read_dataset(const std::string& name, std::vector<hsize_t>* dims = nullptr,
                              hsize_t max_points = kUnbounded) const {
    const Dataset ds = open_dataset(name);
    if (dims != nullptr) *dims = ds.dims();
    return ds.read<T>(max_points);
  }

 private:
  Dataset create_dataset_raw(const std::string& name, hid_t file_type, const Dataspace& space,
                             const PropertyList* creation) const;
};

// The structure probe of io/open_probe.hpp: unless it is switched off or this version of `path`
// passed it before, a forked child reads all of the file through libhdf5 first. Throws
// DamagedFileError (naming `where`'s file, the signal, and that the file was not changed) when
// the child crashed or did not finish in time. File::open calls it; nothing else needs to.
void probe_before_open(const std::string& path, const Where& where);

// A file; as a Group it is the root group "/".
class File : public Group {
 public:
  // Creates (truncating) `path`; `creation` = file creation properties (default: none).
  // `label` = the file's name in error messages ("" = `path`; a temporary copy names its target).
  static File create(const std::string& path, const PropertyList* creation = nullptr,
                     const std::string& label = "");
  // A file held in memory only (HDF5's core driver, no backing store), laid out as create()
  // lays out a file on disk; image() gives its bytes. `label` names it in error messages.
  static File create_in_memory(const std::string& label);
  enum class Access { read_only, read_write };
  // Throws naming the path when it is missing, unreadable or not HDF5.
  static File open(const std::string& path, Access access = Access::read_only,
                   const std::string& label = "");
  // The file exists and has an HDF5 signature.
  static bool is_hdf5(const std::string& path);

  void flush() const;
  // The bytes of the file as they would be on disk now (flush() first).
  std::vector<std::uint8_t> image() const;
  // Closes now and reports a failure (the destructor closes silently).
  void close();

 private:
  File(Id id, Where where) : Group(std::move(id), std::move(where)) {}
};

}  // namespace softevo::io::h5
