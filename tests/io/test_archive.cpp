// Run archive: round trip of every field, atomic updates (a failed update leaves the previous
// file byte for byte), digests that see every deterministic field and ignore timing fields,
// the two forms on disk (a root with segments while running, one file once finished).
#include "io/archive.hpp"
#include "io/h5.hpp"
#include "io/run_lock.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/file.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/io/tmp_dir.hpp"

namespace softevo::io {
namespace {

namespace fs = std::filesystem;

using test::TmpDir;

std::string bytes_of(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunInfo sample_info() {
  RunInfo i;
  i.version = "0.1.0";
  i.git_commit = "abc";
  i.physics_revision = 7;
  i.seed = 3;
  i.ranks = 2;
  i.host = "h";
  i.start_time = "2026-01-01T00:00:00Z";
  i.config_hash = "0123456789abcdef";
  i.experiment = "dir-open";
  return i;
}

GenerationRecord sample_record(std::int64_t g, int n, int ndir) {
  GenerationRecord r;
  r.generation = g;
  r.units = ndir;
  r.component_columns = {"fitness", "direction_deg", "distance", "status"};
  for (int i = 0; i < n; ++i) {
    r.id.push_back(10 * g + i);
    r.parent1.push_back(i == 0 ? -1 : i - 1);
    r.parent2.push_back(-1);
    r.species.push_back(1 + i % 2);
    r.status.push_back(i == 1 ? 4 : 0);
    r.fitness.push_back(0.5 * i + g);
    r.voxels.push_back(20 + i);
    r.chambers.push_back(1 + i);
    r.wall_seconds.push_back(0.25 * i);
    r.worker_rank.push_back(1 + i % 2);
    r.genome.push_back(
        std::vector<std::uint8_t>(static_cast<std::size_t>(5 + i), static_cast<std::uint8_t>(i)));
    for (int d = 0; d < ndir * 4; ++d) r.components.push_back(i * 100.0 + d);
  }
  const FitnessStats s = fitness_stats(r.fitness);
  r.best = s.best;
  r.mean = s.mean;
  r.sd = s.sd;
  r.species_count = 2;
  r.evaluations = n * ndir;
  r.eval_wall_seconds = 1.5;
  return r;
}

TEST(Archive, RoundTripsEveryField) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  create_archive(p, info, "[run]\nseed = 3\n");
  const GenerationRecord r0 = sample_record(0, 4, 5);
  info.generations_done = 1;
  append_generation(p, info, r0, StatsRow{0, r0.best, r0.mean, r0.sd, 2, 7.5},
                    Checkpoint{1, {1, 2, 3}});
  const Archive a(p);
  const RunInfo got = a.info();
  EXPECT_EQ(got.format, "softevo.run/1");
  EXPECT_EQ(got.physics_revision, 7);
  EXPECT_EQ(got.seed, 3);
  EXPECT_EQ(got.ranks, 2);
  EXPECT_EQ(got.experiment, "dir-open");
  EXPECT_EQ(got.state, io::RunState::running);
  EXPECT_EQ(got.generations_done, 1);
  EXPECT_EQ(a.config_text(), "[run]\nseed = 3\n");
  EXPECT_EQ(a.generations(), std::vector<std::int64_t>{0});
  const GenerationRecord g = a.generation(0);
  EXPECT_EQ(g.id, r0.id);
  EXPECT_EQ(g.parent1, r0.parent1);
  EXPECT_EQ(g.species, r0.species);
  EXPECT_EQ(g.status, r0.status);
  EXPECT_EQ(g.fitness, r0.fitness);
  EXPECT_EQ(g.voxels, r0.voxels);
  EXPECT_EQ(g.chambers, r0.chambers);
  EXPECT_EQ(g.wall_seconds, r0.wall_seconds);
  EXPECT_EQ(g.worker_rank, r0.worker_rank);
  EXPECT_EQ(g.genome, r0.genome);
  EXPECT_EQ(g.units, 5);
  EXPECT_EQ(g.component_columns, r0.component_columns);
  EXPECT_EQ(g.components, r0.components);
  EXPECT_EQ(g.best, 1.5);
  EXPECT_EQ(g.evaluations, 20);
  const auto stats = a.stats();
  ASSERT_EQ(stats.size(), 1u);
  EXPECT_EQ(stats[0].evaluations_per_second, 7.5);
  ASSERT_TRUE(a.checkpoint().has_value());
  EXPECT_EQ(a.checkpoint()->generation, 1);
  EXPECT_EQ(a.checkpoint()->population, (std::vector<std::uint8_t>{1, 2, 3}));
  EXPECT_THROW(a.generation(1), ArchiveError);
}

// A checkpoint within a generation (a learning run's state after a round): it replaces the
// root's /checkpoint, stays through state changes and the pack, leaves the digests alone, and
// the next generation's checkpoint has none again.
TEST(Archive, CheckpointWithinAGenerationHoldsItsLearningStateUntilTheNextGeneration) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  create_archive(p, info, "cfg");
  const GenerationRecord r0 = sample_record(0, 4, 1);
  info.generations_done = 1;
  append_generation(p, info, r0, StatsRow{0, r0.best, r0.mean, r0.sd, 2, 1.0}, Checkpoint{1, {5}});
  EXPECT_TRUE(Archive(p).checkpoint()->learning.empty());
  const std::uint64_t content = content_digest(Archive(p));
  const std::uint64_t fitness = fitness_digest(Archive(p));
  // Generation 0 is done: a checkpoint within generation 0 or 2 is refused.
  EXPECT_THROW(update_checkpoint(p, info, Checkpoint{0, {5}, {1}}), ArchiveError);
  EXPECT_THROW(update_checkpoint(p, info, Checkpoint{2, {5}, {1}}), ArchiveError);
  update_checkpoint(p, info, Checkpoint{1, {5}, {7, 8, 9}});
  {
    const Archive a(p);
    EXPECT_EQ(a.checkpoint()->population, (std::vector<std::uint8_t>{5}));
    EXPECT_EQ(a.checkpoint()->learning, (std::vector<std::uint8_t>{7, 8, 9}));
    EXPECT_EQ(a.generations(), std::vector<std::int64_t>{0});
    EXPECT_EQ(a.stats().size(), 1u);
    EXPECT_EQ(content_digest(a), content);
    EXPECT_EQ(fitness_digest(a), fitness);
  }
  info.state = io::RunState::interrupted;
  update_run_info(p, info);
  EXPECT_EQ(Archive(p).checkpoint()->learning, (std::vector<std::uint8_t>{7, 8, 9}));
  finish_archive(p, info);
  ASSERT_TRUE(Archive(p).self_contained());
  EXPECT_EQ(Archive(p).checkpoint()->learning, (std::vector<std::uint8_t>{7, 8, 9}));
  const GenerationRecord r1 = sample_record(1, 4, 1);
  info.generations_done = 2;
  append_generation(p, info, r1, StatsRow{1, r1.best, r1.mean, r1.sd, 2, 1.0}, Checkpoint{2, {6}});
  EXPECT_TRUE(Archive(p).checkpoint()->learning.empty());
}

TEST(Archive, FailedUpdateLeavesThePreviousFileIntact) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  create_archive(p, info, "x");
  const GenerationRecord r0 = sample_record(0, 3, 1);
  append_generation(p, info, r0, StatsRow{}, Checkpoint{1, {9}});
  const std::string before = bytes_of(p);
  // Appending the same generation again fails inside the edit (group exists) ...
  EXPECT_THROW(append_generation(p, info, r0, StatsRow{}, Checkpoint{2, {8}}), ArchiveError);
  // ... and an inconsistent record fails before it.
  GenerationRecord bad = sample_record(1, 3, 1);
  bad.fitness.pop_back();
  EXPECT_THROW(append_generation(p, info, bad, StatsRow{}, Checkpoint{2, {8}}), ArchiveError);
  EXPECT_TRUE(bytes_of(p) == before);
  for (const auto& e : fs::recursive_directory_iterator(d.path)) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name == "run.h5" || name == "run.h5.d" || name == "gen-000000.h5" ||
                name == "reserved-root")
        << "left behind: " << e.path();
  }
}

TEST(Archive, DigestsSeeResultsButNotTiming) {
  TmpDir d;
  const auto make = [&](const std::string& name, auto&& tweak) {
    const std::string p = d.path + "/" + name;
    RunInfo info = sample_info();
    GenerationRecord r = sample_record(0, 4, 1);
    StatsRow s{0, r.best, r.mean, r.sd, 2, 3.0};
    tweak(info, r, s);
    create_archive(p, info, "cfg");
    append_generation(p, info, r, s, Checkpoint{1, {7}});
    const Archive a(p);
    return std::make_pair(fitness_digest(a), content_digest(a));
  };
  const auto base = make("a.h5", [](RunInfo&, GenerationRecord&, StatsRow&) {});
  const auto timing = make("b.h5", [](RunInfo& i, GenerationRecord& r, StatsRow& s) {
    i.host = "other";
    i.ranks = 3;
    i.start_time = "2030-01-01T00:00:00Z";
    r.wall_seconds[0] = 99;
    r.worker_rank[0] = 7;
    r.eval_wall_seconds = 42;
    s.evaluations_per_second = 1e3;
  });
  EXPECT_EQ(base, timing);
  const auto fitness = make("c.h5", [](RunInfo&, GenerationRecord& r, StatsRow&) {
    r.fitness[2] = std::nextafter(r.fitness[2], 10.0);
  });
  EXPECT_NE(base.first, fitness.first);
  EXPECT_NE(base.second, fitness.second);
  const auto genome =
      make("d.h5", [](RunInfo&, GenerationRecord& r, StatsRow&) { r.genome[1][0] ^= 1; });
  EXPECT_EQ(base.first, genome.first);  // fitness digest: only (generation, id, status, fitness)
  EXPECT_NE(base.second, genome.second);
  const auto names = make("e.h5", [](RunInfo&, GenerationRecord& r, StatsRow&) {
    r.component_columns[1] = "heading_change";
  });
  EXPECT_EQ(base.first, names.first);
  EXPECT_NE(base.second, names.second);  // the component names are content
}

TEST(Archive, RejectsForeignAndMissingFiles) {
  TmpDir d;
  EXPECT_THROW(Archive(d.path + "/none.h5"), ArchiveError);
  std::ofstream(d.path + "/text.h5") << "not hdf5";
  EXPECT_THROW(Archive(d.path + "/text.h5"), ArchiveError);
  EXPECT_THROW(check_output_path(d.path + "/no/dir/x.h5"), ArchiveError);
  EXPECT_THROW(check_output_path(d.path), ArchiveError);
  EXPECT_NO_THROW(check_output_path(d.path + "/fine.h5"));
  EXPECT_FALSE(fs::exists(d.path + "/fine.h5"));
  EXPECT_EQ(std::distance(fs::directory_iterator(d.path), fs::directory_iterator()), 1);
  // The archive is never written through a symlink nor over a special file.
  fs::create_symlink(d.path + "/text.h5", d.path + "/link.h5");
  EXPECT_THROW(check_output_path(d.path + "/link.h5"), ArchiveError);
  EXPECT_THROW(check_output_path("/dev/null"), ArchiveError);
}

// Archives written before the physics_revision attribute existed were simulated with revision 1
// (physics/revision.hpp).
TEST(Archive, MissingPhysicsRevisionReadsAsRevisionOne) {
  TmpDir d;
  const std::string p = d.path + "/old.h5";
  create_archive(p, sample_info(), "[run]\nseed = 3\n");
  const hid_t file = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  ASSERT_GE(H5Adelete(file, "physics_revision"), 0);
  H5Fclose(file);
  EXPECT_EQ(Archive(p).info().physics_revision, 1);
}

// The root attribute `state` is one of three names (docs/archive.md); any other value is a
// damaged archive, refused by name rather than read as some state.
TEST(Archive, AnUnknownStateIsRefusedNamingIt) {
  TmpDir d;
  const std::string p = d.path + "/state.h5";
  create_archive(p, sample_info(), "[run]\nseed = 3\n");
  EXPECT_EQ(Archive(p).info().state, RunState::running);
  {
    h5::File file = h5::File::open(p, h5::File::Access::read_write);
    file.write_string_attribute("state", "finished", h5::Charset::utf8);
  }
  try {
    (void)Archive(p).info();
    FAIL() << "an unknown state was read";
  } catch (const ArchiveError& e) {
    EXPECT_NE(std::string(e.what()).find("attribute state = 'finished' is not one of running, "
                                         "complete, interrupted"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

// Archives written before the components were named hold six columns per unit without the
// attribute "columns": they read as the legacy names, and a malformed one is refused.
TEST(Archive, ComponentsWithoutNamesReadAsTheLegacySix) {
  TmpDir d;
  const std::string p = d.path + "/old.h5";
  RunInfo info = sample_info();
  create_archive(p, info, "cfg");
  GenerationRecord r = sample_record(0, 3, 2);
  r.component_columns = legacy_component_columns();
  r.components.clear();
  for (int k = 0; k < 3 * 2 * 6; ++k) r.components.push_back(0.5 * k);
  info.generations_done = 1;
  append_generation(p, info, r, StatsRow{0, r.best, r.mean, r.sd, 2, 1.0}, Checkpoint{1, {7}});
  const std::uint64_t named_digest = content_digest(Archive(p));
  const hid_t file = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  ASSERT_GE(H5Adelete_by_name(file, "/generations/000000/components", "columns", H5P_DEFAULT), 0);
  H5Fclose(file);
  const GenerationRecord g = Archive(p).generation(0);
  EXPECT_EQ(g.component_columns, legacy_component_columns());
  EXPECT_EQ(g.units, 2);
  EXPECT_EQ(g.components, r.components);
  // The legacy layout's digest does not depend on whether its names were written.
  EXPECT_EQ(content_digest(Archive(p)), named_digest);

  const std::string q = d.path + "/odd.h5";
  create_archive(q, info, "cfg");
  append_generation(q, info, sample_record(0, 3, 2), StatsRow{0, 0, 0, 0, 2, 1.0},
                    Checkpoint{1, {7}});
  const hid_t odd = H5Fopen(q.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(odd, 0);
  ASSERT_GE(H5Adelete_by_name(odd, "/generations/000000/components", "columns", H5P_DEFAULT), 0);
  H5Fclose(odd);
  try {
    Archive(q).generation(0);  // four columns without names: not the legacy layout
    FAIL() << "expected an error";
  } catch (const ArchiveError& e) {
    EXPECT_NE(std::string(e.what()).find("components"), std::string::npos) << e.what();
  }
}

// Three generations appended to `p` (a new archive), as a run writes them.
void write_three_generations(const std::string& p, RunInfo& info) {
  create_archive(p, info, "[run]\nseed = 3\n");
  for (std::int64_t g = 0; g < 3; ++g) {
    const GenerationRecord r = sample_record(g, 4, 1);
    info.generations_done = g + 1;
    append_generation(p, info, r, StatsRow{static_cast<double>(g), r.best, r.mean, r.sd, 2, 1.0},
                      Checkpoint{g + 1, {static_cast<std::uint8_t>(g), 7}});
  }
}

// An individual asked for by id alone comes from the last generation that holds it (an elite
// keeps its id in later generations); a generation that does not hold it names those that do.
TEST(Archive, GenerationOfAnIdIsTheLastHoldingItOrNamesWhereItIs) {
  TmpDir d;
  const std::string p = d.path + "/ids.h5";
  RunInfo info = sample_info();
  create_archive(p, info, "[run]\nseed = 3\n");
  for (std::int64_t g = 0; g < 5; ++g) {
    GenerationRecord r = sample_record(g, 2, 1);
    // Id 5 in generations 0, 1, 3 and 4; every generation has one id of its own.
    r.id = g == 2 ? std::vector<std::int64_t>{100 + g, 200} : std::vector<std::int64_t>{5, 100 + g};
    info.generations_done = g + 1;
    append_generation(p, info, r, StatsRow{static_cast<double>(g), r.best, r.mean, r.sd, 2, 1.0},
                      Checkpoint{g + 1, {1}});
  }
  const Archive a(p);
  EXPECT_EQ(a.generation_of(5), 4);
  EXPECT_EQ(a.generation_of(5, 1), 1);
  EXPECT_EQ(a.generation_of(200), 2);
  EXPECT_EQ(a.generation_of(102, 2), 2);
  const auto error_of = [&](std::int64_t id, std::optional<std::int64_t> g) -> std::string {
    try {
      a.generation_of(id, g);
    } catch (const ArchiveError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error_of(5, 2), p + ": generation 2 has no individual with id 5; it is in "
                                "generations 0..1, 3..4");
  EXPECT_EQ(error_of(200, 4), p + ": generation 4 has no individual with id 200; it is in "
                                  "generation 2");
  EXPECT_EQ(
      error_of(7, std::nullopt),
      p + ": no generation has an individual with id 7 (the archive's ids run from 5 to 200)");
  EXPECT_EQ(error_of(7, 0), p + ": generation 0 has no individual with id 7, nor has any other "
                                "generation (the archive's ids run from 5 to 200)");
  EXPECT_EQ(error_of(5, 9), p + ": no generation 9; the archive has generations 0..4");
}

// While a run writes, the archive is a small root whose generations are links to one segment
// file each; finish_archive packs it into one file with the same content and removes them.
TEST(Archive, RootWithSegmentsReadsAsAndPacksIntoOneFile) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  std::uint64_t running_content = 0;
  {
    const Archive a(p);
    EXPECT_FALSE(a.self_contained());
    const std::vector<GenerationStorage> storage = a.generation_storage();
    ASSERT_EQ(storage.size(), 3u);
    EXPECT_EQ(storage[2].file, "run.h5.d/gen-000002.h5");
    EXPECT_EQ(storage[2].object, "/generations/000002");
    EXPECT_EQ(a.generation(2).id, sample_record(2, 4, 1).id);
    EXPECT_EQ(a.stored_generation_digest(1), generation_digest(sample_record(1, 4, 1)));
    EXPECT_EQ(a.stats().size(), 3u);
    EXPECT_EQ(a.checkpoint()->population, (std::vector<std::uint8_t>{2, 7}));
    running_content = content_digest(a);
  }
  // The root holds no generation data: its size does not depend on the generations' data.
  EXPECT_LT(fs::file_size(p), fs::file_size(d.path + "/run.h5.d/gen-000002.h5") * 3);

  // Packed with the same root attributes, the content is the same, digest for digest.
  finish_archive(p, info);
  EXPECT_FALSE(fs::exists(d.path + "/run.h5.d"));
  const Archive a(p);
  EXPECT_TRUE(a.self_contained());
  EXPECT_EQ(a.info().state, io::RunState::running);
  EXPECT_EQ(a.generation(1).genome, sample_record(1, 4, 1).genome);
  EXPECT_EQ(a.stored_generation_digest(2), generation_digest(sample_record(2, 4, 1)));
  EXPECT_EQ(content_digest(a), running_content);
}

// Appending to a self-contained archive (a finished run continued, or an older build's file)
// moves that file unchanged into the segment directory and links its generations.
TEST(Archive, AppendingToAPackedArchiveKeepsItsFileAsASegment) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  info.state = io::RunState::interrupted;
  finish_archive(p, info);
  const std::string packed_bytes = bytes_of(p);
  const GenerationRecord r = sample_record(3, 4, 1);
  info.generations_done = 4;
  append_generation(p, info, r, StatsRow{3, r.best, r.mean, r.sd, 2, 1.0}, Checkpoint{4, {9}});
  EXPECT_TRUE(bytes_of(d.path + "/run.h5.d/packed-000003.h5") == packed_bytes);
  const Archive a(p);
  const std::vector<GenerationStorage> storage = a.generation_storage();
  ASSERT_EQ(storage.size(), 4u);
  EXPECT_EQ(storage[0].file, "run.h5.d/packed-000003.h5");
  EXPECT_EQ(storage[3].file, "run.h5.d/gen-000003.h5");
  for (std::int64_t g = 0; g < 4; ++g) EXPECT_EQ(a.generation(g).id, sample_record(g, 4, 1).id);
  EXPECT_EQ(a.stats().size(), 4u);
}

TEST(Archive, MissingSegmentIsNamed) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  fs::remove(d.path + "/run.h5.d/gen-000001.h5");
  const Archive a(p);
  EXPECT_EQ(a.generation(0).id, sample_record(0, 4, 1).id);
  try {
    a.generation(1);
    ADD_FAILURE() << "a missing segment was read";
  } catch (const ArchiveError& e) {
    EXPECT_NE(std::string(e.what()).find("run.h5.d/gen-000001.h5, which is missing"),
              std::string::npos)
        << e.what();
  }
}

// What a killed writer leaves - its temporaries, a segment no root names yet - is removed;
// what the root references and what live processes write is kept.
TEST(Archive, DebrisOfADeadWriterIsRemoved) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  const std::string seg = d.path + "/run.h5.d/";
  const std::vector<std::string> debris = {
      d.path + "/.run.h5.tmp.999999999.AbC123",  // beyond pid_max: never alive
      d.path + "/.run.h5.tmp.999999999",         // an older build's temporary
      seg + ".gen-000003.h5.tmp.999999999.xYz789", seg + "gen-000003.h5"};
  const std::vector<std::string> kept = {
      d.path + "/.run.h5.tmp." + std::to_string(::getpid()) + ".AbC123",
      d.path + "/.other.h5.tmp.999999999", seg + "notes.txt"};
  for (const auto& f : debris) std::ofstream(f) << "x";
  for (const auto& f : kept) std::ofstream(f) << "x";
  EXPECT_EQ(remove_archive_debris(p), 4);
  for (const auto& f : debris) EXPECT_FALSE(fs::exists(f)) << f;
  for (const auto& f : kept) EXPECT_TRUE(fs::exists(f)) << f;
  for (std::int64_t g = 0; g < 3; ++g) EXPECT_EQ(Archive(p).generation(g).id.size(), 4u);
  // A finished archive references no segment: they all go, the directory with them once empty.
  fs::remove(seg + "notes.txt");
  info.state = io::RunState::complete;
  finish_archive(p, info);
  EXPECT_FALSE(fs::exists(seg));
}

TEST(Archive, FitnessStatsUsePopulationSd) {
  const FitnessStats s = fitness_stats({1.0, 3.0});
  EXPECT_EQ(s.best, 3.0);
  EXPECT_EQ(s.mean, 2.0);
  EXPECT_EQ(s.sd, 1.0);
}

// A tmpfs of `size` mounted at d.path/small (root only): its path, or "" (errno says why).
std::string mount_small_tmpfs(const TmpDir& d, const char* size) {
  const std::string mnt = d.path + "/small";
  fs::create_directory(mnt);
  const std::string options = std::string("size=") + size;
  return ::mount("tmpfs", mnt.c_str(), "tmpfs", 0, options.c_str()) == 0 ? mnt : "";
}

// A pack that the file system cannot take is refused before it writes anything (issue 29:
// libhdf5 1.10 crashed in H5Ocopy when the disk filled during the copy): a real 1 MiB tmpfs
// (root only; skipped elsewhere) left with less free space than the archive's files take.
TEST(Archive, PackRefusedWithoutRoomAndArchiveKept) {
  TmpDir d;
  const std::string mnt = mount_small_tmpfs(d, "1m");
  if (mnt.empty())
    GTEST_SKIP() << "cannot mount a small tmpfs (" << std::strerror(errno) << "; needs root)";
  const test::LazyUnmount unmount{mnt};
  const std::string p = mnt + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  std::uint64_t content = 0;
  {
    const Archive a(p);
    content = content_digest(a);
  }
  std::uint64_t archive_bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(mnt))
    if (e.is_regular_file()) archive_bytes += e.file_size();
  // Fill the disk up to about the archive's own size: too little for a second copy.
  std::uint64_t free_bytes = fs::space(mnt).available;
  ASSERT_GT(free_bytes, archive_bytes);
  {
    std::ofstream filler(mnt + "/filler", std::ios::binary);
    const std::string block(4096, 'x');
    for (std::uint64_t n = 0; n + archive_bytes / 2 < free_bytes; n += block.size())
      filler.write(block.data(), static_cast<std::streamsize>(block.size()));
  }
  free_bytes = fs::space(mnt).available;
  ASSERT_LT(free_bytes, archive_bytes);
  try {
    finish_archive(p, info);
    ADD_FAILURE() << "packed into " << free_bytes << " free bytes";
  } catch (const ArchiveError& e) {
    EXPECT_NE(std::string(e.what()).find("not packed into one file"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("No space left on device"), std::string::npos) << e.what();
  }
  const Archive a(p);
  EXPECT_FALSE(a.self_contained());
  EXPECT_EQ(content_digest(a), content);
  for (const auto& e : fs::directory_iterator(mnt))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

// Fills the file system of `dir` with a file `dir`/filler until fewer than `leave` bytes are
// free (ENOSPC ends it early): another process taking the space.
void fill_disk(const std::string& dir, std::uint64_t leave) {
  const int fd = ::open((dir + "/filler").c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) return;
  const std::string block(4096, 'x');
  while (fs::space(dir).available >= leave + block.size())
    if (::write(fd, block.data(), block.size()) <= 0) break;
  ::close(fd);
}

// A root with segments of three generations whose checkpoint takes `checkpoint_bytes`.
void write_run_with_checkpoint(const std::string& p, RunInfo& info, std::size_t checkpoint_bytes) {
  create_archive(p, info, "[run]\nseed = 3\n");
  for (std::int64_t g = 0; g < 3; ++g) {
    const GenerationRecord r = sample_record(g, 40, 3);
    info.generations_done = g + 1;
    std::vector<std::uint8_t> population(checkpoint_bytes);
    for (std::size_t i = 0; i < population.size(); ++i)
      population[i] = static_cast<std::uint8_t>(i * 7 + static_cast<std::size_t>(g));
    append_generation(p, info, r, StatsRow{static_cast<double>(g), r.best, r.mean, r.sd, 2, 1.0},
                      Checkpoint{g + 1, population});
  }
}

// Issue 29: on a shared, full disk the stop's new root found no room beside the old one, and
// the archive stayed `running` (4 of 31 packed full-disk scan sizes). The space reserved at
// every root write takes it: on a disk with not one block free, the stop still records
// `interrupted` with the longest stop reason, and the archive is otherwise unchanged.
TEST(Archive, StopStateRecordedOnAFullDisk) {
  TmpDir d;
  const std::string mnt = mount_small_tmpfs(d, "2m");
  if (mnt.empty())
    GTEST_SKIP() << "cannot mount a small tmpfs (" << std::strerror(errno) << "; needs root)";
  const test::LazyUnmount unmount{mnt};
  const std::string p = mnt + "/run.h5";
  RunInfo info = sample_info();
  write_run_with_checkpoint(p, info, 200'000);  // a root of about 200 kB
  std::uint64_t fitness = 0;
  {
    const Archive a(p);
    fitness = fitness_digest(a);
  }
  fill_disk(mnt, 0);
  ASSERT_LT(fs::space(mnt).available, 4096u);
  info.state = io::RunState::interrupted;
  info.end_time = "2026-01-01T01:00:00Z";
  info.stop_reason = std::string(static_cast<std::size_t>(ArchiveLimits::string_bytes), 'r');
  update_run_info(p, info);
  const Archive a(p);
  EXPECT_EQ(a.info().state, io::RunState::interrupted);
  EXPECT_EQ(a.info().stop_reason, info.stop_reason);
  EXPECT_EQ(a.info().generations_done, 3);
  EXPECT_EQ(fitness_digest(a), fitness);
  EXPECT_EQ(a.checkpoint()->population.size(), 200'000u);
  for (const auto& e : fs::recursive_directory_iterator(mnt))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  // The reservation is used up; a state change that keeps the run going never takes it.
  EXPECT_FALSE(fs::exists(mnt + "/run.h5.d/reserved-root"));
}

// The reserved space follows the root: it holds the root's size and a margin after every
// root write, and goes with the segments when the archive is packed or removed.
TEST(Archive, ReservedSpaceForTheStopFollowsTheRoot) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  const std::string reserve = d.path + "/run.h5.d/reserved-root";
  RunInfo info = sample_info();
  create_archive(p, info, "[run]\nseed = 3\n");
  ASSERT_TRUE(fs::exists(reserve));
  EXPECT_GE(fs::file_size(reserve), fs::file_size(p));
  write_run_with_checkpoint(p, info, 100'000);
  EXPECT_GE(fs::file_size(reserve), fs::file_size(p) + 16 * 1024);
  // Allocated, not a hole: 512-byte blocks.
  struct stat st {};
  ASSERT_EQ(::stat(reserve.c_str(), &st), 0);
  EXPECT_GE(static_cast<std::uint64_t>(st.st_blocks) * 512, fs::file_size(p));
  EXPECT_EQ(remove_archive_debris(p), 0);  // kept for a running archive
  EXPECT_TRUE(fs::exists(reserve));
  finish_archive(p, info);
  EXPECT_FALSE(fs::exists(d.path + "/run.h5.d"));
}

// Issue 29: another process filling the disk during the pack crashed libhdf5 (SIGSEGV in
// H5Ocopy), and with it the run. The pack runs in a child process: a crash there (here made
// by the step hook, in the pack's process) is an error naming the signal, the archive stays
// as it was (root and segments, no temporary), and this process lives on.
TEST(Archive, CrashWhilePackingKillsOnlyThePacksProcess) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  const std::uint64_t content = content_digest(Archive(p));
  const std::string root_bytes = bytes_of(p);
  // In a child of the test too: before the fix the crash killed the process that packed.
  const pid_t test_child = ::fork();
  ASSERT_GE(test_child, 0);
  if (test_child == 0) {
    int code = 0;
    try {
      finish_archive(p, info, [](const std::string& step) {
        if (step == "pack: /generations") ::raise(SIGSEGV);
      });
      code = 1;
    } catch (const ArchiveError& e) {
      const std::string m = e.what();
      if (m.find("not packed into one file") == std::string::npos ||
          m.find("signal 11") == std::string::npos)
        code = 2;
    }
    ::_exit(code);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(test_child, &status, 0), test_child);
  ASSERT_FALSE(WIFSIGNALED(status)) << "the packing process died of signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: packed, 2: the error does not name the crash";
  EXPECT_EQ(bytes_of(p), root_bytes);
  const Archive a(p);
  EXPECT_FALSE(a.self_contained());
  EXPECT_EQ(content_digest(a), content);
  for (const auto& e : fs::recursive_directory_iterator(d.path))
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
}

// The same with a real disk: another process fills the tmpfs after the free-space check, while
// the generations are being copied, leaving 0 to 64 kB free. Whatever libhdf5 does then (an
// error, or a crash of the pack's process), the pack fails cleanly and the archive is kept.
TEST(Archive, DiskFilledDuringThePackKeepsTheArchive) {
  TmpDir d;
  const std::string mnt = mount_small_tmpfs(d, "4m");
  if (mnt.empty())
    GTEST_SKIP() << "cannot mount a small tmpfs (" << std::strerror(errno) << "; needs root)";
  const test::LazyUnmount unmount{mnt};
  const std::string p = mnt + "/run.h5";
  RunInfo info = sample_info();
  write_run_with_checkpoint(p, info, 100'000);
  const std::uint64_t content = content_digest(Archive(p));
  for (const std::uint64_t leave : std::initializer_list<std::uint64_t>{0, 4096, 16384, 65536}) {
    SCOPED_TRACE("disk filled to " + std::to_string(leave) + " bytes free during the pack");
    const pid_t test_child = ::fork();
    ASSERT_GE(test_child, 0);
    if (test_child == 0) {
      int code = 0;
      try {
        finish_archive(p, info, [&](const std::string& step) {
          if (step == "pack: /generations") fill_disk(mnt, leave);
        });
        code = 1;
      } catch (const ArchiveError& e) {
        if (std::string(e.what()).find("not packed into one file") == std::string::npos) code = 2;
      }
      ::_exit(code);
    }
    int status = 0;
    ASSERT_EQ(::waitpid(test_child, &status, 0), test_child);
    EXPECT_FALSE(WIFSIGNALED(status)) << "the packing process died of signal " << WTERMSIG(status);
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 0)
        << "1: packed on a full disk, 2: another error";
    fs::remove(mnt + "/filler");
    const Archive a(p);
    EXPECT_FALSE(a.self_contained());
    EXPECT_EQ(content_digest(a), content);
    for (const auto& e : fs::recursive_directory_iterator(mnt))
      EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
}

// An archive another process holds an flock on (libhdf5's file locking of a writer, e.g.
// h5py) is refused by libhdf5 and looked like "neither a robot file nor a trace" to softevo
// view (issue 29); the note says it is locked, by which run, and how to proceed.
TEST(Archive, LockedArchiveIsNamedLocked) {
  TmpDir d;
  const std::string p = d.path + "/run.h5";
  RunInfo info = sample_info();
  write_three_generations(p, info);
  EXPECT_FALSE(locked_file_note(p).has_value());
  // flock locks belong to an open file description: one of our own conflicts like another
  // process's would.
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  EXPECT_FALSE(is_run_archive(p));
  std::optional<std::string> note = locked_file_note(p);
  ASSERT_TRUE(note.has_value());
  EXPECT_NE(note->find("locked by another process"), std::string::npos) << *note;
  EXPECT_NE(note->find("copy the file"), std::string::npos) << *note;
  {
    const RunLock run(p, "node7");
    note = locked_file_note(p);
    ASSERT_TRUE(note.has_value());
    EXPECT_NE(note->find("a running job writes this archive: pid"), std::string::npos) << *note;
    EXPECT_NE(note->find("node7"), std::string::npos) << *note;
  }
  ::close(fd);
  EXPECT_FALSE(locked_file_note(p).has_value());
  EXPECT_TRUE(is_run_archive(p));
}

}  // namespace
}  // namespace softevo::io
