// Output files: write_file_atomically / prepare_output_file (missing folders made, as mkdir -p;
// a folder that cannot be made is one line naming the path and why), and write_pairs_csv.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

TEST(AtomicFile, WritesTheContent) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  write_file_atomically(path, [](std::ostream& out) { out << "hello\nworld\n"; });
  EXPECT_EQ(read_text(path), "hello\nworld\n");
  // Replaces an existing file.
  write_file_atomically(path, [](std::ostream& out) { out << "second"; });
  EXPECT_EQ(read_text(path), "second");
  // Binary mode keeps bytes as they are.
  const std::string bytes("a\0b\r\n\xff", 6);
  write_file_atomically(
      dir.file("bin"), [&](std::ostream& out) { out.write(bytes.data(), 6); }, true);
  EXPECT_EQ(read_text(dir.file("bin")), bytes);
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"bin", "out.txt"}));
}

TEST(AtomicFile, FailingCallbackLeavesTheOldFileAndNoTemporary) {
  TempDir dir;
  const std::string path = dir.file("results.csv");
  write_text(path, "precious old content\n");
  // The callback has written part of its output when it fails.
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "half-written new content";
                                       throw InputError("simulated failure");
                                     }),
               InputError);
  EXPECT_EQ(read_text(path), "precious old content\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"results.csv"});
  // Without an old file: nothing is left at all.
  const std::string fresh = dir.file("fresh.csv");
  EXPECT_ANY_THROW(write_file_atomically(fresh, [](std::ostream& out) {
    out << "partial";
    throw std::runtime_error("boom");
  }));
  EXPECT_FALSE(std::filesystem::exists(fresh));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"results.csv"});
}

// atomic_file.hpp: "On any error (from `write` or from the stream) the temporary file is
// removed, `path` is untouched, and InputError is thrown naming the file." An exception of
// another type from the callback must therefore come out as InputError naming the file.
TEST(AtomicFile, AnyCallbackErrorBecomesInputErrorNamingTheFile) {
  TempDir dir;
  const std::string path = dir.file("results.csv");
  write_text(path, "old\n");
  try {
    write_file_atomically(path, [](std::ostream& out) {
      out << "partial";
      throw std::runtime_error("boom");
    });
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected InputError naming " << path
                  << ", got another exception: " << e.what();
  }
  EXPECT_EQ(read_text(path), "old\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"results.csv"});
}

TEST(AtomicFile, StreamFailureIsAnInputError) {
  TempDir dir;
  const std::string path = dir.file("s.txt");
  write_text(path, "old");
  EXPECT_THROW(write_file_atomically(path,
                                     [](std::ostream& out) {
                                       out << "x";
                                       out.setstate(std::ios::badbit);
                                     }),
               InputError);
  EXPECT_EQ(read_text(path), "old");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"s.txt"});
}

TEST(AtomicFile, MakesTheMissingFoldersAsMkdirP) {
  TempDir dir;
  const std::string path = dir.file("no/such/dir/out.csv");
  write_file_atomically(path, [](std::ostream& out) { out << "made\n"; });
  EXPECT_EQ(read_text(path), "made\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"no"});
  // Nothing but the file in its folder: the temporary was renamed.
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir.path() / "no/such/dir")) {
    names.push_back(e.path().filename().string());
  }
  EXPECT_EQ(names, std::vector<std::string>{"out.csv"});
  // A trailing separator and "." / ".." in the folder are as mkdir -p takes them.
  write_file_atomically(dir.file("a/./b/../c/out.csv"), [](std::ostream& out) { out << "x"; });
  EXPECT_EQ(read_text(dir.file("a/c/out.csv")), "x");
  EXPECT_TRUE(std::filesystem::is_directory(dir.path() / "a/b"));
}

TEST(AtomicFile, PrepareOutputFile) {
  TempDir dir;
  EXPECT_NO_THROW(prepare_output_file(dir.file("new.csv")));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{}) << "a file was created by preparing";
  // Missing folders are made, the file is not.
  EXPECT_NO_THROW(prepare_output_file(dir.file("missing/deeper/new.csv")));
  EXPECT_TRUE(std::filesystem::is_directory(dir.path() / "missing/deeper"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "missing/deeper/new.csv"));
  // A path that is a folder cannot be written as a file.
  std::filesystem::create_directory(dir.path() / "sub");
  EXPECT_THROW(prepare_output_file(dir.file("sub")), InputError);
  EXPECT_THROW(write_file_atomically(dir.file("sub"), [](std::ostream& out) { out << "x"; }),
               InputError);
  EXPECT_TRUE(std::filesystem::is_directory(dir.path() / "sub"));
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"missing", "sub"}));
}

// A file where a folder of the path should be: one line naming the path, the folder and the
// file in the way; the file is untouched, the callback never runs, and an existing output
// elsewhere is not touched either.
TEST(AtomicFile, AFileInTheWayIsOneLineNamingItAndNothingIsLost) {
  TempDir dir;
  write_text(dir.file("blocker"), "a file, not a folder\n");
  for (const std::string& path : {dir.file("blocker/out.csv"), dir.file("blocker/a/b/out.csv")}) {
    try {
      prepare_output_file(path);
      ADD_FAILURE() << "no exception for " << path;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path + ": cannot create the folder '", 0), 0u) << message;
      EXPECT_NE(message.find("'" + dir.file("blocker") + "' is a file, not a folder"),
                std::string::npos)
          << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
    bool called = false;
    EXPECT_THROW(write_file_atomically(path, [&](std::ostream&) { called = true; }), InputError);
    EXPECT_FALSE(called) << "the callback ran although the file cannot be written";
  }
  EXPECT_EQ(read_text(dir.file("blocker")), "a file, not a folder\n");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"blocker"});
}

// No permission to make the folder: the message gives the system's reason. (Root may write
// anywhere: skipped there.)
TEST(AtomicFile, AFolderThatMayNotBeMadeIsOneLineWithTheReason) {
  if (::geteuid() == 0) GTEST_SKIP() << "root may make folders anywhere";
  TempDir dir;
  std::filesystem::create_directory(dir.path() / "locked");
  ::chmod(dir.file("locked").c_str(), 0500);
  const std::string path = dir.file("locked/a/out.csv");
  try {
    prepare_output_file(path);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path + ": cannot create the folder '", 0), 0u) << message;
    EXPECT_NE(message.find("ermission denied"), std::string::npos) << message;
  }
  ::chmod(dir.file("locked").c_str(), 0700);
}

// ----------------------------------------------------------------------------------------------

TEST(PairsCsv, HeaderThenAscendingPairsWithILessThanJ) {
  TempDir dir;
  const ContactList list = list_from_pairs(6, {{4, 1}, {0, 5}, {2, 3}, {0, 1}, {3, 5}, {1, 2}});
  const std::string path = dir.file("pairs.csv");
  write_pairs_csv(list, path);
  EXPECT_EQ(read_text(path), "i,j\n0,1\n0,5\n1,2\n1,4\n2,3\n3,5\n");
}

TEST(PairsCsv, EmptyListIsOnlyTheHeader) {
  TempDir dir;
  write_pairs_csv(ContactList{}, dir.file("a.csv"));
  EXPECT_EQ(read_text(dir.file("a.csv")), "i,j\n");
  write_pairs_csv(list_from_pairs(4, {}), dir.file("b.csv"));
  EXPECT_EQ(read_text(dir.file("b.csv")), "i,j\n");
}

TEST(PairsCsv, MatchesTheDetectedContacts) {
  SceneSpec spec;
  spec.kind = SceneKind::kBlobs;
  spec.n = 3000;
  spec.diameter = 0.02;
  spec.seed = 14;
  const Scene scene = generate_scene(spec);
  const Detected got = detect(scene, parse_variant("cell/morton/half/dynamic,7"), spec.diameter, 2);
  TempDir dir;
  const std::string path = dir.file("pairs.csv");
  write_pairs_csv(got.contacts, path);
  std::istringstream in(read_text(path));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "i,j");
  std::pair<long, long> previous{-1, -1};
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    ASSERT_NE(comma, std::string::npos) << line;
    const long i = std::stol(line.substr(0, comma));
    const long j = std::stol(line.substr(comma + 1));
    ASSERT_LT(i, j) << line;
    ASSERT_LT(previous, std::make_pair(i, j)) << "not ascending at " << line;
    previous = {i, j};
    pairs.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
  }
  EXPECT_EQ(pairs.size(), got.contacts.pair_count());
  EXPECT_TRUE(same_contacts(list_from_pairs(scene.size(), pairs),
                            brute_force_contacts(scene, spec.diameter)));
}

TEST(PairsCsv, MakesAMissingFolderAndFailsCleanlyForAFileInTheWay) {
  TempDir dir;
  write_pairs_csv(list_from_pairs(2, {{0, 1}}), dir.file("missing/pairs.csv"));
  EXPECT_EQ(read_text(dir.file("missing/pairs.csv")), "i,j\n0,1\n");
  write_text(dir.file("blocker"), "kept");
  EXPECT_THROW(write_pairs_csv(list_from_pairs(2, {{0, 1}}), dir.file("blocker/pairs.csv")),
               InputError);
  EXPECT_EQ(read_text(dir.file("blocker")), "kept");
}

}  // namespace
}  // namespace contactlab::test
