// The MPI modes against the serial run, run under `mpirun -np K` for several K (CTest label
// mpi): the --contacts-out file of replicated and decomposed detection is byte for byte the
// serial one on the hard cases (lattice ties, cell faces, coincident particles, everything in
// one cell, D larger than the box, N = 0 and 1, near-ties, shifted boxes), on clustered
// scenes whose clusters straddle subdomain boundaries, with per-particle diameters, and with
// ranks whose subdomain is empty. Every rank runs every test; rank 0 compares.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene_io.hpp"
#include "contactlab/mpi/distributed_detect.hpp"
#include "contactlab/mpi/runtime.hpp"
#include "test_support.hpp"

namespace contactlab::test {
namespace {

int rank() { return mpi::rank_of(MPI_COMM_WORLD); }
int ranks() { return mpi::size_of(MPI_COMM_WORLD); }

// A folder every rank sees, named by rank 0.
std::string shared_dir(const std::string& name) {
  std::string path;
  if (rank() == 0) {
    path = (std::filesystem::path(::testing::TempDir()) /
            ("contactlab_mpi_" + name + "_" + std::to_string(::getpid())))
               .string();
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  int length = static_cast<int>(path.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  path.resize(length);
  MPI_Bcast(path.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  return path;
}

// The serial run's file, written by rank 0.
std::string serial_csv(const Scene& scene, const Variant& variant, double d,
                       const std::string& path) {
  if (rank() == 0) {
    ContactDetector detector;
    DetectOptions options;
    options.variant = variant;
    options.diameter = d;
    options.threads = 1;
    detector.run(scene, options);
    write_pairs_csv(detector.canonical_contacts(), path);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return path;
}

// Runs `mode` on every rank and checks on rank 0 that its file equals the serial one, and on
// every rank that the contact total agrees.
void expect_same_as_serial(const std::string& name, const Scene& scene, double d,
                           const Variant& variant, mpi::Mode mode, int threads = 1) {
  const std::string dir = shared_dir(name);
  const std::string want = serial_csv(scene, variant, d, dir + "/serial.csv");
  mpi::MpiOptions options;
  options.mode = mode;
  options.block = 7;  // small blocks: every rank gets some even on small scenes
  options.contacts_out = dir + "/mpi.csv";
  mpi::SceneSource source;
  source.scene = &scene;
  DetectOptions detect{variant, d, threads, nullptr};
  const mpi::MpiRun run = mpi::detect(MPI_COMM_WORLD, source, detect, options);
  EXPECT_EQ(run.particles, scene.size());
  if (rank() == 0) {
    const std::string got = read_text(options.contacts_out);
    const std::string expected = read_text(want);
    EXPECT_EQ(got, expected) << name << " " << to_string(variant) << " " << to_string(mode)
                             << " on " << ranks() << " ranks";
    std::size_t files = 0;
    for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++files;
    EXPECT_EQ(files, 2u) << "a temporary file was left behind";
    std::uint64_t emitted = 0;
    for (const auto& r : run.all) emitted += r.contact_pairs;
    EXPECT_EQ(emitted, run.contact_pairs);
    std::filesystem::remove_all(dir);
  }
  MPI_Barrier(MPI_COMM_WORLD);
}

std::vector<Variant> tested_variants(mpi::Mode mode) {
  std::vector<Variant> variants;
  for (const char* text : {"particle/sorted/full/static,200", "particle/morton/half/dynamic,7",
                           "cell/unsorted/half/guided,1", "cell/sorted/full/static"}) {
    variants.push_back(parse_variant(text));
  }
  // Single precision rounds coordinates relative to the box: the decomposed mode's local
  // boxes round differently near D, so only the replicated mode must match it exactly.
  if (mode == mpi::Mode::kReplicated) {
    variants.push_back(parse_variant("particle/sorted/full/dynamic,3/float"));
  }
  return variants;
}

struct NamedScene {
  std::string name;
  Scene scene;
  double d;
};

std::vector<NamedScene> hard_scenes() {
  std::vector<NamedScene> scenes;
  // A 6x6x6 lattice at spacing exactly D: every axis neighbour touches (ties).
  {
    std::vector<Point> points;
    for (int k = 0; k < 6; ++k)
      for (int j = 0; j < 6; ++j)
        for (int i = 0; i < 6; ++i) points.push_back({i * 0.125, j * 0.125, k * 0.125});
    scenes.push_back({"lattice_ties", make_scene(points), 0.125});
  }
  // Particles on cell faces and on the box's upper faces.
  {
    std::vector<Point> points;
    for (int i = 0; i <= 8; ++i) {
      points.push_back({i * 0.125, 0.5, 0.5});
      points.push_back({1.0, i * 0.125, 1.0});
      points.push_back({0.5, 1.0, i * 0.125});
    }
    scenes.push_back({"faces", make_scene(points), 0.125});
  }
  // Coincident particles, and everything in one cell.
  scenes.push_back(
      {"coincident",
       make_scene({{0.3, 0.3, 0.3}, {0.3, 0.3, 0.3}, {0.3, 0.3, 0.3}, {0.9, 0.9, 0.9}}), 0.01});
  {
    std::vector<Point> points;
    points.reserve(40);
    for (int i = 0; i < 40; ++i) points.push_back({0.5 + 1e-3 * (i % 5), 0.5, 0.5 + 1e-3 * i});
    scenes.push_back({"one_cell", make_scene(points), 0.1});
  }
  scenes.push_back({"d_larger_than_box", make_scene({{0.1, 0.1, 0.1}, {0.9, 0.9, 0.9}}), 5.0});
  scenes.push_back({"empty", make_scene({}), 0.1});
  scenes.push_back({"single", make_scene({{0.5, 0.5, 0.5}}), 0.1});
  // Near-ties: pairs at D (1 -/+ 1e-12), along a line crossing many cells.
  {
    std::vector<Point> points;
    const double d = 0.05;
    for (int i = 0; i < 12; ++i) {
      const double x = 0.02 + i * 0.08;
      points.push_back({x, 0.5, 0.5});
      points.push_back({x + d * (i % 2 ? 1 - 1e-12 : 1 + 1e-12), 0.5, 0.5});
    }
    scenes.push_back({"near_ties", make_scene(points), 0.05});
  }
  // A box far from the origin and not a cube.
  {
    Box box{{100.0, -50.0, 7.0}, {102.0, -49.0, 7.5}};
    SceneSpec spec;
    spec.kind = SceneKind::kUniform;
    spec.n = 1500;
    spec.diameter = 0.04;
    spec.seed = 3;
    spec.box = box;
    scenes.push_back({"shifted_box", generate_scene(spec), spec.diameter});
  }
  return scenes;
}

class MpiModes : public ::testing::TestWithParam<mpi::Mode> {};

TEST_P(MpiModes, HardCasesMatchTheSerialRun) {
  for (const NamedScene& s : hard_scenes()) {
    for (const Variant& variant : tested_variants(GetParam())) {
      expect_same_as_serial(s.name, s.scene, s.d, variant, GetParam());
    }
  }
}

// Blobs: several dense clusters, which the work split cuts through (the boundaries between
// ranks run through the clusters, where the work is); and the paper's clustered scene.
TEST_P(MpiModes, ClustersStraddlingSubdomainBoundariesMatchTheSerialRun) {
  SceneSpec spec;
  spec.kind = SceneKind::kBlobs;
  spec.n = 6000;
  spec.diameter = 0.02;
  spec.seed = 9;
  spec.blob_count = 3;
  const Scene blobs = generate_scene(spec);
  spec.kind = SceneKind::kClustered;
  spec.n = 8000;
  const Scene clustered = generate_scene(spec);
  for (const Variant& variant : tested_variants(GetParam())) {
    expect_same_as_serial("blobs", blobs, spec.diameter, variant, GetParam(), 2);
    expect_same_as_serial("clustered", clustered, spec.diameter, variant, GetParam(), 1);
  }
}

TEST_P(MpiModes, PerParticleDiametersMatchTheSerialRun) {
  SceneSpec spec;
  spec.kind = SceneKind::kPolydisperse;
  spec.n = 3000;
  spec.diameter = 0.04;
  spec.seed = 4;
  const Scene scene = generate_scene(spec);
  expect_same_as_serial("polydisperse", scene, 0.0, parse_variant("particle/sorted/full/static"),
                        GetParam());
}

INSTANTIATE_TEST_SUITE_P(Both, MpiModes,
                         ::testing::Values(mpi::Mode::kReplicated, mpi::Mode::kDecomposed),
                         [](const ::testing::TestParamInfo<mpi::Mode>& param) {
                           return std::string(mpi::to_string(param.param));
                         });

// Two particles and more ranks than that: the others own nothing and still take part.
TEST(Decomposed, RanksWithAnEmptySubdomainWork) {
  const Scene scene = make_scene({{0.1, 0.1, 0.1}, {0.12, 0.1, 0.1}});
  const std::string dir = shared_dir("empty_subdomain");
  mpi::MpiOptions options;
  options.mode = mpi::Mode::kDecomposed;
  options.contacts_out = dir + "/pairs.csv";
  mpi::SceneSource source;
  source.scene = &scene;
  const Variant variant = parse_variant("particle/sorted/full/static");
  const mpi::MpiRun run =
      mpi::detect(MPI_COMM_WORLD, source, DetectOptions{variant, 0.05, 1, nullptr}, options);
  EXPECT_EQ(run.contact_pairs, 1u);
  if (rank() == 0) {
    EXPECT_EQ(read_text(options.contacts_out), "i,j\n0,1\n");
    int empty = 0;
    std::uint64_t owned = 0;
    for (const auto& r : run.all) {
      empty += r.owned_particles == 0;
      owned += r.owned_particles;
    }
    EXPECT_EQ(owned, 2u);
    if (ranks() > 2) {
      EXPECT_GE(empty, ranks() - 2);
    }
    std::filesystem::remove_all(dir);
  }
}

// A failure only one rank sees (its share of the particles holds a NaN) ends every rank's call
// with an exception: InputError on the rank that saw it, ReportedElsewhere on the others.
TEST(Decomposed, AFailureOnOneRankReachesEveryRank) {
  Scene scene = make_scene({{0.1, 0.1, 0.1}, {0.2, 0.2, 0.2}, {0.3, 0.3, 0.3}, {0.4, 0.4, 0.4}});
  const std::string dir = shared_dir("failure");
  // A binary file whose last particle (in the last rank's share) is outside the box.
  scene.x.back() = 2.0;
  const std::string path = dir + "/bad.bin";
  if (rank() == 0) write_binary_scene(scene, path);  // the writer does not validate, readers do
  MPI_Barrier(MPI_COMM_WORLD);
  mpi::MpiOptions options;
  options.mode = mpi::Mode::kDecomposed;
  options.contacts_out = dir + "/pairs.csv";
  mpi::SceneSource source;
  source.path = path;
  const Variant variant = parse_variant("particle/sorted/full/static");
  bool reported = false, elsewhere = false;
  try {
    mpi::detect(MPI_COMM_WORLD, source, DetectOptions{variant, 0.05, 1, nullptr}, options);
  } catch (const InputError& e) {
    reported = true;
    EXPECT_NE(std::string(e.what()).find("particle 3"), std::string::npos) << e.what();
  } catch (const ReportedElsewhere&) {
    elsewhere = true;
  }
  EXPECT_TRUE(reported || elsewhere);
  EXPECT_EQ(reported, rank() == ranks() - 1);
  int reporters = reported ? 1 : 0, total = 0;
  MPI_Allreduce(&reporters, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, 1);
  if (rank() == 0) {
    EXPECT_FALSE(std::filesystem::exists(options.contacts_out));
    std::filesystem::remove_all(dir);
  }
}

}  // namespace
}  // namespace contactlab::test

// On ranks other than 0: only the failed assertions, with the rank.
class FailurePrinter : public ::testing::EmptyTestEventListener {
  void OnTestPartResult(const ::testing::TestPartResult& result) override {
    if (!result.failed()) return;
    std::fprintf(stderr, "[rank %d] %s:%d: %s\n", contactlab::mpi::rank_of(MPI_COMM_WORLD),
                 result.file_name() ? result.file_name() : "?", result.line_number(),
                 result.summary());
  }
};

// GoogleTest under MPI: every rank runs the tests; rank 0 prints the progress, the others
// their failures only.
int main(int argc, char** argv) {
  const contactlab::mpi::Session session(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (contactlab::mpi::rank_of(MPI_COMM_WORLD) != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new FailurePrinter);
  }
  const int failed = RUN_ALL_TESTS();
  int any = 0;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return any;  // the session finalises MPI
}
