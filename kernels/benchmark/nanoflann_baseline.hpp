// The contact search a nanoflann user would write for our problem, the baseline the kernels are
// measured against (neighbour_search_benchmark.cpp): a k-d tree over the scene's points
// (nanoflann 1.4, Debian's libnanoflann-dev; its build is serial) and one radius query per
// particle on OpenMP threads, each row of partners written to a contact list in input rows.
//
// What a careful user does, so that the comparison is with nanoflann at its best: the queries
// run in the tree's leaf order (neighbouring queries walk the same nodes and points, in cache),
// under a dynamic schedule (the clustered scene's dense centre costs more per query), the
// partners go straight to a thread's buffer through a result set of our own (no index-distance
// pairs, no sorting), and the rows are assembled in parallel as the detector assembles its own.
//
// The contact decision is the detector's bit for bit: nanoflann's L2_Simple_Adaptor sums
// (a - b)^2 over x, y, z in that order as pair_test.hpp does, and it keeps a point when its
// distance is below the result set's worstDist(), which is the next double above D^2, so that
// `<` there is `<=` D^2. Monodisperse scenes only (a radius query has one radius).
#pragma once

#include <omp.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <vector>

#include "contactlab/kernels/contact_list.hpp"
#include "contactlab/kernels/error.hpp"
#include "contactlab/kernels/scene.hpp"

namespace contactlab::baseline {

// The scene as nanoflann's dataset: points by index and dimension, the box as the bounding box
// (so the build need not compute it).
struct SceneCloud {
  const Scene* scene;
  std::size_t kdtree_get_point_count() const { return scene->size(); }
  double kdtree_get_pt(std::uint32_t i, std::size_t dim) const {
    return dim == 0 ? scene->x[i] : dim == 1 ? scene->y[i] : scene->z[i];
  }
  template <class BoundingBox>
  bool kdtree_get_bbox(BoundingBox& box) const {
    for (int axis = 0; axis < 3; ++axis) {
      box[axis].low = scene->box.lo[axis];
      box[axis].high = scene->box.hi[axis];
    }
    return true;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<double, SceneCloud, double, std::uint32_t>, SceneCloud, 3,
    std::uint32_t>;

// nanoflann's result-set protocol: appends every point within the radius but the query itself.
class PartnerSink {
 public:
  PartnerSink(double limit, std::uint32_t self, std::vector<std::uint32_t>& out)
      : limit_(limit), self_(self), out_(out), first_(out.size()) {}
  double worstDist() const { return limit_; }
  bool full() const { return true; }
  std::size_t size() const { return out_.size() - first_; }
  bool addPoint(double, std::uint32_t index) {
    if (index != self_) out_.push_back(index);
    return true;  // never stop early: every partner is wanted
  }

 private:
  double limit_;
  std::uint32_t self_;
  std::vector<std::uint32_t>& out_;
  std::size_t first_;
};

struct NanoflannRun {
  double build_s = 0.0;   // the tree
  double search_s = 0.0;  // the queries and the contact list
  double total_s() const { return build_s + search_s; }
};

// Holds the tree and the buffers between runs, as ContactDetector holds its own.
class NanoflannContacts {
 public:
  // Throws InputError for per-particle diameters, a diameter that is not positive and finite, a
  // leaf size of 0 or fewer than one thread.
  NanoflannRun run(const Scene& scene, double diameter, int threads, std::size_t leaf_size) {
    if (scene.has_diameters()) {
      throw InputError("the nanoflann baseline takes one diameter (a radius query has one radius)");
    }
    if (!(diameter > 0.0) || !std::isfinite(diameter)) {
      throw InputError("diameter must be a positive finite number, got " + number_text(diameter));
    }
    if (leaf_size < 1 || threads < 1) throw InputError("leaf size and threads must be >= 1");
    const auto n = static_cast<std::uint32_t>(scene.size());
    NanoflannRun result;
    const double start = omp_get_wtime();
    cloud_ = {&scene};
    tree_ =
        std::make_unique<KdTree>(3, cloud_, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size));
    tree_->buildIndex();
    const double built = omp_get_wtime();
    result.build_s = built - start;

    const double limit = std::nextafter(diameter * diameter, std::numeric_limits<double>::max());
    count_.resize(n);
    buffers_.resize(static_cast<std::size_t>(threads));
    visited_.resize(static_cast<std::size_t>(threads));
    contacts_.offsets.resize(std::size_t{n} + 1);
    const std::uint32_t* const leaf_order = tree_->vAcc.data();
#pragma omp parallel num_threads(threads)
    {
      const auto t = static_cast<std::size_t>(omp_get_thread_num());
      std::vector<std::uint32_t>& mine = buffers_[t];
      std::vector<std::uint32_t>& homes = visited_[t];
      mine.clear();
      homes.clear();
      const nanoflann::SearchParams params(32, 0.0, false);
#pragma omp for schedule(dynamic, 256)
      for (std::uint32_t k = 0; k < n; ++k) {
        const std::uint32_t i = leaf_order[k];
        const double point[3] = {scene.x[i], scene.y[i], scene.z[i]};
        PartnerSink sink(limit, i, mine);
        tree_->findNeighbors(sink, point, params);
        count_[i] = static_cast<std::uint32_t>(sink.size());
        homes.push_back(i);
      }
#pragma omp single
      {
        std::uint64_t running = 0;
        for (std::uint32_t i = 0; i < n; ++i) {
          contacts_.offsets[i] = running;
          running += count_[i];
        }
        contacts_.offsets[n] = running;
        contacts_.partners.resize(running);
      }  // implicit barrier
      const std::uint32_t* row = mine.data();
      for (const std::uint32_t i : homes) {
        std::memcpy(contacts_.partners.data() + contacts_.offsets[i], row,
                    count_[i] * sizeof(std::uint32_t));
        row += count_[i];
      }
    }
    result.search_s = omp_get_wtime() - built;
    return result;
  }

  // Rows in input order, each row's partners in the order the tree found them.
  const ContactList& contacts() const { return contacts_; }

 private:
  SceneCloud cloud_{};
  std::unique_ptr<KdTree> tree_;
  std::vector<std::uint32_t> count_;
  std::vector<std::vector<std::uint32_t>> buffers_, visited_;
  ContactList contacts_;
};

}  // namespace contactlab::baseline
