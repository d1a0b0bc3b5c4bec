// See h5_heap.hpp. The checks are by hand on the file's bytes: libhdf5 offers no validated path.
#include "io/h5_heap.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>

namespace softevo::io::h5 {
namespace {

// ---- variable-length data, read from the file's bytes ------------------------------------------
//
// HDF5 keeps variable-length strings and sequences in global heap collections (HDF5 file format
// specification, "Global Heap"): an element's raw data is the sequence length (u32), the file
// address of a collection and the index of an object in it (u32). libhdf5 1.10 trusts all three
// and the object sizes inside the collection: a flipped length made it allocate and clear up
// to 2 x 4 GiB per element (the 73 s / 8.4 GB `softevo info` of issue 21), a flipped object size
// made it copy past its buffers (SIGSEGV), a zero free-space size would make its parser loop
// for ever. So datasets of variable-length data are read here, each reference checked against
// the collections of the file, and before libhdf5 itself reads a variable-length attribute every
// collection of the file is checked (the attribute's references sit in checksummed object
// headers or dense attribute storage in the archive's format; the collections have no checksum).

// The file an object lives in (an external link's target for a linked object), for raw reads.
struct RawFile {
  Id file;                  // keeps the file open while its descriptor is used
  int fd = -1;              // the sec2 driver's descriptor
  std::uint64_t base = 0;   // byte offset of file address 0 (the user block's size)
  std::uint64_t bytes = 0;  // size of the file
  std::size_t address_size = 8;
  std::size_t length_size = 8;
  std::string key;  // device, inode, size and modification time: the cache key
};

RawFile raw_file_of(hid_t object, const Where& where, const std::string& action) {
  RawFile raw;
  raw.file = Id(where.check(H5Iget_file_id(object), action), H5Fclose);
  unsigned intent = 0;
  where.check_status(H5Fget_intent(raw.file.get(), &intent), action);
  // What this process wrote through HDF5 may still sit in its caches.
  if ((intent & H5F_ACC_RDWR) != 0)
    where.check_status(H5Fflush(raw.file.get(), H5F_SCOPE_LOCAL), action);
  const Id access(where.check(H5Fget_access_plist(raw.file.get()), action), H5Pclose);
  if (H5Pget_driver(access.get()) != H5FD_SEC2)
    where.fail(action, "variable-length data is read only from files of HDF5's default driver");
  void* handle = nullptr;
  where.check_status(H5Fget_vfd_handle(raw.file.get(), H5P_DEFAULT, &handle), action);
  raw.fd = *static_cast<int*>(handle);
  const Id creation(where.check(H5Fget_create_plist(raw.file.get()), action), H5Pclose);
  hsize_t user_block = 0;
  where.check_status(H5Pget_sizes(creation.get(), &raw.address_size, &raw.length_size), action);
  where.check_status(H5Pget_userblock(creation.get(), &user_block), action);
  if (raw.address_size > 8 || raw.length_size > 8 || raw.address_size == 0 || raw.length_size == 0)
    where.fail(action, "file addresses or lengths wider than 8 bytes");
  raw.base = user_block;
  struct stat st {};
  if (::fstat(raw.fd, &st) != 0) where.fail(action, std::string("fstat: ") + std::strerror(errno));
  raw.bytes = static_cast<std::uint64_t>(st.st_size);
  raw.key = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino) + ":" +
            std::to_string(st.st_size) + ":" + std::to_string(st.st_mtim.tv_sec) + "." +
            std::to_string(st.st_mtim.tv_nsec);
  return raw;
}

// Reads `n` bytes at `offset`; false when the file is shorter or the read fails.
bool read_at(const RawFile& f, std::uint64_t offset, void* out, std::size_t n) {
  if (offset > f.bytes || n > f.bytes - offset) return false;
  auto* p = static_cast<char*>(out);
  while (n > 0) {
    const ssize_t got = ::pread(f.fd, p, n, static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    p += got;
    n -= static_cast<std::size_t>(got);
    offset += static_cast<std::uint64_t>(got);
  }
  return true;
}

std::uint64_t little_endian(const unsigned char* p, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

struct HeapObject {
  std::uint64_t offset = 0;  // byte offset of the object's data in the file
  std::uint64_t size = 0;    // bytes
};

struct HeapCollection {
  std::string problem;                          // "" = well formed
  std::map<std::uint64_t, HeapObject> objects;  // by object index
};

// Every global heap collection of one file, by byte offset.
struct HeapIndex {
  std::map<std::uint64_t, HeapCollection> collections;
  std::string first_problem;  // of the first malformed collection; "" = all well formed
};

// Parses the collection whose signature is at byte `at`; nothing when the bytes there are not
// a collection libhdf5 would accept (wrong version or reserved bytes: it refuses those itself).
void index_collection(const RawFile& f, std::uint64_t at, HeapIndex& index) {
  const std::size_t header = 8 + f.length_size;         // signature, version, reserved, size
  const std::size_t object_header = 8 + f.length_size;  // index, references, reserved, size
  unsigned char h[16] = {0};
  if (!read_at(f, at, h, header)) return;
  if (h[4] != 1 || h[5] != 0 || h[6] != 0 || h[7] != 0) return;
  HeapCollection c;
  const std::uint64_t size = little_endian(h + 8, f.length_size);
  const std::string name = "global heap collection at byte " + std::to_string(at);
  const auto bad = [&](const std::string& why) {
    c.problem = name + ": " + why;
    c.objects.clear();
  };
  if (size < header || size > f.bytes - at) {
    bad("its size " + std::to_string(size) + " runs past the end of the file");
  } else {
    std::uint64_t pos = header;
    while (pos < size && size - pos >= object_header) {
      unsigned char o[16] = {0};
      if (!read_at(f, at + pos, o, object_header)) {
        bad("unreadable");
        break;
      }
      const auto object = static_cast<std::uint64_t>(little_endian(o, 2));
      const std::uint64_t bytes = little_endian(o + 8, f.length_size);
      if (object == 0) {  // free space, its size including its header
        if (bytes < object_header || bytes > size - pos || bytes % 8 != 0) {
          bad("free space of " + std::to_string(bytes) + " bytes at offset " + std::to_string(pos) +
              " does not fit");
          break;
        }
        pos += bytes;
        continue;
      }
      const std::uint64_t room = size - pos - object_header;
      if (bytes > room || (bytes + 7) / 8 * 8 > room) {
        bad("object " + std::to_string(object) + " of " + std::to_string(bytes) +
            " bytes runs past the end of the collection");
        break;
      }
      if (!c.objects.emplace(object, HeapObject{at + pos + object_header, bytes}).second) {
        bad("object " + std::to_string(object) + " appears twice");
        break;
      }
      pos += object_header + (bytes + 7) / 8 * 8;
    }
  }
  if (!c.problem.empty() && index.first_problem.empty()) index.first_problem = c.problem;
  index.collections[at] = std::move(c);
}

std::shared_ptr<const HeapIndex> build_heap_index(const RawFile& f, const Where& where,
                                                  const std::string& action) {
  auto index = std::make_shared<HeapIndex>();
  constexpr std::size_t kBlock = std::size_t{1} << 20;
  constexpr char kSignature[] = "GCOL";
  // No larger than the file: a small file is scanned without clearing a megabyte first.
  std::vector<char> block(static_cast<std::size_t>(std::min<std::uint64_t>(kBlock, f.bytes)) + 3);
  for (std::uint64_t start = 0; start < f.bytes; start += kBlock) {
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(block.size(), f.bytes - start));
    if (!read_at(f, start, block.data(), n)) where.fail(action, "cannot read the file");
    // A signature is counted in the block where it starts; the 3 extra bytes catch one that
    // straddles two blocks.
    const char* p = block.data();
    const char* const end = block.data() + n;
    while (p < end) {
      const void* hit = ::memmem(p, static_cast<std::size_t>(end - p), kSignature, 4);
      if (hit == nullptr) break;
      const auto offset = static_cast<std::size_t>(static_cast<const char*>(hit) - block.data());
      if (offset >= kBlock) break;
      index_collection(f, start + offset, *index);
      p = static_cast<const char*>(hit) + 1;
    }
  }
  return index;
}

// The heap index of `f`, built once per version of the file's contents.
std::shared_ptr<const HeapIndex> heap_index(const RawFile& f, const Where& where,
                                            const std::string& action) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const HeapIndex>> cache;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto found = cache.find(f.key);
    if (found != cache.end()) return found->second;
  }
  auto index = build_heap_index(f, where, action);
  const std::lock_guard<std::mutex> lock(mutex);
  // Bounded: a process that reads many files keeps only the latest ones.
  if (cache.size() >= 64) cache.clear();
  cache[f.key] = index;
  return index;
}

}  // namespace

// Before libhdf5 reads a variable-length attribute of `object`: every collection of its file
// is well formed.
void check_heaps_before_library_read(hid_t object, const Where& where, const std::string& action) {
  const RawFile f = raw_file_of(object, where, action);
  const auto index = heap_index(f, where, action);
  if (!index->first_problem.empty()) where.fail(action, index->first_problem);
}

// The variable-length rows of a contiguous dataset, each checked against the global heap.
std::vector<std::vector<std::uint8_t>> read_vlen_rows(hid_t dataset, const Where& where,
                                                      hsize_t rows, hsize_t max_row_bytes) {
  const std::string action = "read dataset";
  std::vector<std::vector<std::uint8_t>> out;
  if (rows == 0) return out;
  const RawFile f = raw_file_of(dataset, where, action);
  const Id creation(where.check(H5Dget_create_plist(dataset), action), H5Pclose);
  if (H5Pget_layout(creation.get()) != H5D_CONTIGUOUS)
    where.fail(action, "variable-length data not stored contiguously is not supported");
  const std::uint64_t reference = 4 + f.address_size + 4;  // length, collection, object
  const haddr_t offset = H5Dget_offset(dataset);
  const hsize_t storage = H5Dget_storage_size(dataset);
  if (offset == HADDR_UNDEF) where.fail(action, "has no data stored");
  if (rows > f.bytes / reference || storage != rows * reference)
    where.fail(action, std::to_string(rows) + " rows need " + std::to_string(rows * reference) +
                           " bytes of references, the dataset stores " + std::to_string(storage));
  std::vector<unsigned char> refs(static_cast<std::size_t>(storage));
  if (!read_at(f, offset, refs.data(), refs.size()))
    where.fail(action, "its data runs past the end of the file");
  const auto index = heap_index(f, where, action);
  std::uint64_t total = 0;
  out.resize(static_cast<std::size_t>(rows));
  for (std::size_t i = 0; i < out.size(); ++i) {
    const unsigned char* r = refs.data() + i * reference;
    const std::uint64_t length = little_endian(r, 4);
    if (length == 0) continue;
    const std::string row = "row " + std::to_string(i);
    if (length > max_row_bytes) where.fail(action, row + " " + too_long(length, max_row_bytes));
    const std::uint64_t collection = f.base + little_endian(r + 4, f.address_size);
    const std::uint64_t object = little_endian(r + 4 + f.address_size, 4);
    const auto c = index->collections.find(collection);
    if (c == index->collections.end())
      where.fail(action, row + " refers to no global heap collection (byte " +
                             std::to_string(collection) + ")");
    if (!c->second.problem.empty()) where.fail(action, row + ": " + c->second.problem);
    const auto o = c->second.objects.find(object);
    if (o == c->second.objects.end())
      where.fail(action, row + " refers to object " + std::to_string(object) +
                             ", missing in the global heap collection at byte " +
                             std::to_string(collection));
    if (o->second.size != length)
      where.fail(action, row + " claims " + std::to_string(length) +
                             " bytes, its heap object has " + std::to_string(o->second.size));
    // Each row is its own object in a file this layer wrote, so together they fit in the file;
    // rows sharing one object could otherwise multiply it.
    total += length;
    if (total > f.bytes) where.fail(action, "rows hold more bytes than the file");
    out[i].resize(static_cast<std::size_t>(length));
    if (!read_at(f, o->second.offset, out[i].data(), out[i].size()))
      where.fail(action, row + ": unreadable");
  }
  return out;
}

}  // namespace softevo::io::h5
