// The RAII layer over the HDF5 C API (io/h5.hpp): round trips of every kind of object it
// writes, handles closed by their destructors, and failures that name file, object and reason
// without HDF5 printing its error stack.
#include "io/h5.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/io/tmp_dir.hpp"

namespace softevo::io::h5 {
namespace {

namespace fs = std::filesystem;

using test::TmpDir;

ssize_t open_hdf5_objects() {
  return H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
}

// The failure of `call` as an h5::Error (fails the test when it does not throw one).
template <typename Call>
Error error_of(Call&& call) {
  try {
    call();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no h5::Error thrown";
  return Error("", "", "", "");
}

TEST(H5, NumbersStringsAndAttributesRoundTrip) {
  TmpDir d;
  const std::string path = d.file("a.h5");
  {
    const File file = File::create(path);
    const Group g = file.create_group("group");
    g.write_dataset<double>("doubles", {2, 3}, {1.5, -2.0, 3.25, 4.0, 5.0, 6.0});
    g.write_dataset<float>("floats", {2}, {0.25f, 0.5f});
    g.write_dataset<std::int32_t>("ints", {3}, {-1, 0, 7});
    g.write_dataset<std::int64_t>("longs", {1}, {1LL << 40});
    g.write_dataset<std::uint8_t>("bytes", {0}, {});
    g.write_byte_rows("rows", {{1, 2, 3}, {}, {255}});
    file.write_string_dataset("text", "héllo", Charset::utf8);
    g.write_string_dataset("ascii", "plain", Charset::ascii);
    g.write_attribute<double>("x", 0.125);
    g.write_attribute<std::int64_t>("n", -5);
    g.write_attribute<std::int64_t>("n", 6);  // replaces
    file.write_string_attribute("format", "test/1", Charset::utf8);
  }
  const File file = File::open(path);
  const Group g = file.open_group("group");
  std::vector<hsize_t> dims;
  EXPECT_EQ(g.read_dataset<double>("doubles", &dims),
            (std::vector<double>{1.5, -2.0, 3.25, 4.0, 5.0, 6.0}));
  EXPECT_EQ(dims, (std::vector<hsize_t>{2, 3}));
  EXPECT_EQ(g.read_dataset<double>("floats"), (std::vector<double>{0.25, 0.5}));
  EXPECT_EQ(g.read_dataset<std::int32_t>("ints"), (std::vector<std::int32_t>{-1, 0, 7}));
  EXPECT_EQ(g.read_dataset<std::int64_t>("longs"), (std::vector<std::int64_t>{1LL << 40}));
  EXPECT_TRUE(g.read_dataset<std::uint8_t>("bytes").empty());
  EXPECT_EQ(g.open_dataset("rows").read_byte_rows(),
            (std::vector<std::vector<std::uint8_t>>{{1, 2, 3}, {}, {255}}));
  EXPECT_EQ(file.open_dataset("text").read_string(), "héllo");
  EXPECT_EQ(g.open_dataset("ascii").read_string(), "plain");
  EXPECT_EQ(g.read_attribute<double>("x"), 0.125);
  EXPECT_EQ(g.read_attribute<std::int64_t>("n"), 6);
  EXPECT_EQ(g.read_attribute<double>("n"), 6.0);  // integers convert to doubles
  EXPECT_EQ(file.read_string_attribute("format"), "test/1");
  EXPECT_TRUE(file.has_link("group/doubles"));
  EXPECT_FALSE(file.has_link("nothing/doubles"));
  EXPECT_EQ(g.link_names(), (std::vector<std::string>{"ascii", "bytes", "doubles", "floats", "ints",
                                                      "longs", "rows"}));
}

TEST(H5, OnDiskNumbersAreLittleEndianWhateverTheHost) {
  TmpDir d;
  const std::string path = d.file("le.h5");
  {
    const File file = File::create(path);
    file.write_dataset<double>("d", {1}, {1.0});
    file.write_attribute<std::int32_t>("i", 1);
  }
  const File file = File::open(path);
  const Id type(H5Dget_type(file.open_dataset("d").id()), H5Tclose);
  EXPECT_GT(H5Tequal(type.get(), H5T_IEEE_F64LE), 0);
  const Id attr(H5Aopen(file.id(), "i", H5P_DEFAULT), H5Aclose);
  const Id attr_type(H5Aget_type(attr.get()), H5Tclose);
  EXPECT_GT(H5Tequal(attr_type.get(), H5T_STD_I32LE), 0);
}

TEST(H5, GrowableDatasetTakesBlocks) {
  TmpDir d;
  const std::string path = d.file("grow.h5");
  {
    const File file = File::create(path);
    PropertyList creation = PropertyList::dataset_creation();
    creation.chunk({4, 2});
    const Dataset ds = file.create_dataset<double>(
        "table", Dataspace::simple({0, 2}, {H5S_UNLIMITED, 2}), &creation);
    for (hsize_t row = 0; row < 3; ++row) {
      ds.set_extent({row + 1, 2});
      ds.write_block<double>({row, 0}, {1, 2}, {static_cast<double>(row), 10.0 + row});
    }
    EXPECT_THROW(ds.write_block<double>({0, 0}, {1, 2}, {1.0}), Error);  // 1 value for 2
  }
  std::vector<hsize_t> dims;
  EXPECT_EQ(File::open(path).read_dataset<double>("table", &dims),
            (std::vector<double>{0, 10, 1, 11, 2, 12}));
  EXPECT_EQ(dims, (std::vector<hsize_t>{3, 2}));
}

// Issue 21 item 4: no read allocates more than its limit or its file allows, whatever extent
// or length the file claims; the error names the file, the object and the limit.
TEST(H5, ReadsAreBoundedByTheirLimitAndByTheFile) {
  TmpDir d;
  const std::string path = d.file("bounds.h5");
  {
    const File file = File::create(path);
    file.write_dataset<double>("three", {3}, {1, 2, 3});
    file.write_string_dataset("text", "twelve bytes", Charset::utf8);
    file.write_string_attribute("label", "twelve bytes", Charset::utf8);
    file.write_byte_rows("rows", {{1, 2, 3}, {4}});
    // A growable dataset whose extent claims 2^40 rows that were never written: reading it
    // would fill 8 TiB in memory with its fill value.
    PropertyList creation = PropertyList::dataset_creation();
    creation.chunk({16});
    const Dataset huge =
        file.create_dataset<double>("huge", Dataspace::simple({0}, {H5S_UNLIMITED}), &creation);
    huge.set_extent({hsize_t{1} << 40});
  }
  const File file = File::open(path);
  EXPECT_EQ(file.read_dataset<double>("three", nullptr, 3).size(), 3u);
  const Error over = error_of([&] { file.read_dataset<double>("three", nullptr, 2); });
  EXPECT_EQ(over.file(), path);
  EXPECT_EQ(over.object(), "/three");
  EXPECT_NE(over.reason().find("3 values, more than the limit of 2"), std::string::npos);
  const Error huge = error_of([&] { file.read_dataset<double>("huge"); });
  EXPECT_EQ(huge.object(), "/huge");
  EXPECT_NE(huge.reason().find("more than its file"), std::string::npos) << huge.what();
  EXPECT_EQ(file.open_dataset("text").read_string(12), "twelve bytes");
  EXPECT_NE(error_of([&] { file.open_dataset("text").read_string(11); })
                .reason()
                .find("12 bytes long, more than the limit of 11 bytes"),
            std::string::npos);
  EXPECT_EQ(file.read_string_attribute("label", 12), "twelve bytes");
  EXPECT_THROW(file.read_string_attribute("label", 11), Error);
  EXPECT_EQ(file.open_dataset("rows").read_byte_rows(2, 3).size(), 2u);
  EXPECT_NE(error_of([&] { file.open_dataset("rows").read_byte_rows(1, 3); })
                .reason()
                .find("2 rows, more than the limit of 1"),
            std::string::npos);
  EXPECT_NE(error_of([&] { file.open_dataset("rows").read_byte_rows(2, 2); })
                .reason()
                .find("row 0 is 3 bytes long"),
            std::string::npos);
  EXPECT_NE(
      error_of([&] { file.link_names(3); }).reason().find("4 links, more than the limit of 3"),
      std::string::npos);
}

TEST(H5, FixedLengthStringsWrittenByOtherToolsAreRead) {
  TmpDir d;
  const std::string path = d.file("fixed.h5");
  {
    const File file = File::create(path);
    const Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), 8);
    const Dataspace scalar = Dataspace::scalar();
    const Id attr(H5Acreate2(file.id(), "label", type.get(), scalar.id(), H5P_DEFAULT, H5P_DEFAULT),
                  H5Aclose);
    const char text[8] = {'a', 'b', 'c', 0, 0, 0, 0, 0};
    ASSERT_GE(H5Awrite(attr.get(), type.get(), text), 0);
  }
  EXPECT_EQ(File::open(path).read_string_attribute("label"), "abc");
}

TEST(H5, HandlesAreClosedByTheirDestructors) {
  TmpDir d;
  const std::string path = d.file("close.h5");
  const ssize_t before = open_hdf5_objects();
  {
    const File file = File::create(path);
    const Group g = file.create_group("g");
    const Dataset ds = g.write_dataset<double>("v", {1}, {2.0});
    EXPECT_GE(open_hdf5_objects(), before + 3);
    ds.write_attribute<double>("a", 1.0);
  }
  EXPECT_EQ(open_hdf5_objects(), before);
  {
    File file = File::open(path, File::Access::read_write);
    file.open_group("g").open_dataset("v").read<double>();
    file.close();
    EXPECT_EQ(open_hdf5_objects(), before);
    file.close();  // a second close does nothing
  }
  // Moving hands the id over: one close, not two.
  Id a(H5Screate(H5S_SCALAR), H5Sclose);
  const hid_t raw = a.get();
  Id b(std::move(a));
  EXPECT_FALSE(a.valid());
  EXPECT_EQ(b.get(), raw);
  EXPECT_GT(H5Iis_valid(raw), 0);
  b.reset();
  EXPECT_LE(H5Iis_valid(raw), 0);
}

TEST(H5, FailingCallNamesFileObjectAndReason) {
  TmpDir d;
  const std::string path = d.file("err.h5");
  const File file = File::create(path);
  const Group g = file.create_group("generations");
  // HDF5 itself refuses (the name exists): its reason is captured, not printed.
  testing::internal::CaptureStderr();
  const Error twice = error_of([&] { file.create_group("generations"); });
  const std::string printed = testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "") << "HDF5 printed its error stack";
  EXPECT_EQ(twice.file(), path);
  EXPECT_EQ(twice.object(), "/generations");
  EXPECT_EQ(twice.action(), "create group");
  EXPECT_FALSE(twice.reason().empty());
  EXPECT_NE(std::string(twice.what()).find(path + ": /generations: create group: "),
            std::string::npos)
      << twice.what();

  const Error missing = error_of([&] { g.open_dataset("fitness"); });
  EXPECT_EQ(missing.object(), "/generations/fitness");
  EXPECT_EQ(missing.reason(), "no such dataset");

  g.write_string_attribute("label", "x", Charset::utf8);
  const Error not_number = error_of([&] { g.read_attribute<double>("label"); });
  EXPECT_EQ(not_number.object(), "/generations");
  EXPECT_NE(not_number.action().find("'label'"), std::string::npos);

  g.write_dataset<double>("real", {1}, {0.5});
  const Error not_integer = error_of([&] { g.read_dataset<std::int64_t>("real"); });
  EXPECT_EQ(not_integer.object(), "/generations/real");
  EXPECT_EQ(not_integer.reason(), "is not an integer");

  // The error stack is empty after a captured failure: the next message is not a stale one.
  EXPECT_EQ(take_error_message(), "");
}

TEST(H5, OpeningMissingOrForeignFilesNamesThePath) {
  TmpDir d;
  const Error none = error_of([&] { File::open(d.file("none.h5")); });
  EXPECT_EQ(none.file(), d.file("none.h5"));
  EXPECT_EQ(none.reason(), "no such file");
  std::ofstream(d.file("text.h5")) << "not hdf5";
  const Error text = error_of([&] { File::open(d.file("text.h5")); });
  EXPECT_NE(text.reason().find("not an HDF5 file"), std::string::npos);
  EXPECT_FALSE(File::is_hdf5(d.file("text.h5")));
  EXPECT_FALSE(File::is_hdf5(d.file("none.h5")));
  EXPECT_FALSE(File::is_hdf5(d.path));
  // A file in a directory that does not exist: HDF5's own reason.
  testing::internal::CaptureStderr();
  const Error nodir = error_of([&] { File::create(d.file("no/dir/x.h5")); });
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(nodir.file(), d.file("no/dir/x.h5"));
  EXPECT_EQ(nodir.action(), "create file");
  EXPECT_FALSE(nodir.reason().empty());
  // The label replaces the path in messages (a temporary copy names its target).
  const Error labelled =
      error_of([&] { File::open(d.file("none.h5"), File::Access::read_only, "run.h5"); });
  EXPECT_EQ(labelled.file(), "run.h5");
}

// Not a regular file: refused by name before libhdf5 opens it (issue 39: a FIFO blocked `info`,
// `view`, `replay`, ... and Python's open_run forever; a directory was "not an HDF5 file").
TEST(H5, AFifoOrADirectoryIsRefusedWithoutBlocking) {
  TmpDir d;
  ASSERT_EQ(::mkfifo(d.file("pipe.h5").c_str(), 0600), 0);
  const Error fifo = error_of([&] { File::open(d.file("pipe.h5")); });
  EXPECT_EQ(fifo.file(), d.file("pipe.h5"));
  EXPECT_EQ(fifo.reason(), "is a FIFO (named pipe), not an HDF5 file");
  EXPECT_FALSE(File::is_hdf5(d.file("pipe.h5")));
  const Error dir = error_of([&] { File::open(d.path); });
  EXPECT_EQ(dir.reason(), "is a directory, not an HDF5 file");
  const Error device = error_of([&] { File::open("/dev/null"); });
  EXPECT_EQ(device.reason(), "is a character device, not an HDF5 file");
}

}  // namespace
}  // namespace softevo::io::h5
