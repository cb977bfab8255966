// A contact-detection variant as a value: what the CLI parses, the tuner enumerates, the
// benchmarks register and the tests iterate. Each axis is declared once, in the table of
// variant_axes() (variant.cpp): parsing, printing, `contactlab variants` and all_variants()
// come from it.
//
// Text form: the positional axes loop/order/stencil/schedule, e.g.
// "particle/sorted/full/static,200" (the three-part "loop/order/schedule" means the paper's
// full stencil), then any other axis as a named part `name=value`, printed only when it is not
// the default. Precision keeps its older bare form too: a fifth part "float" is
// "precision=float", and float variants print that way. The grid index prints as
// "grid=dense" or "grid=hashed" ("grid=auto", the default, not at all), e.g.
// "cell/sorted/full/static/grid=hashed".
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace contactlab {

// What one parallel iteration is: a cell of the grid (paper Fig. 4) or a particle (Fig. 5).
enum class LoopKind { kCell, kParticle };

// Memory order of the particles during detection: input order, grouped by cell in the
// grid's linear (z, y, x) order as in the paper, or grouped by cell in Morton (Z-curve) order
// of the cells, which keeps neighbouring cells closer in memory.
enum class Order { kUnsorted, kSorted, kMorton };

// The paper's 27-cell stencil tests every pair twice (once from each particle); the half
// stencil (own cell + 13 forward neighbours) tests it once and writes both partner lists.
enum class Stencil { kFull, kHalf };

// kBalanced is no OpenMP schedule: one consecutive block per thread like static's, its bounds
// where the estimated work (candidate tests from the cell occupancies, plus a cost per home)
// reaches an equal share, so that a clustered scene's dense blocks do not fall to a few threads
// (the block schedule of the sorted particle loop ran 5.1x on 16 Xeon cores, its chunks 10.6x).
enum class ScheduleKind { kStatic, kDynamic, kGuided, kBalanced };

// Arithmetic of the pair test: double (the reference) or float (coordinates relative to the
// box's lower corner, rounded to single precision: half the memory traffic). Float finds the
// same contacts: the pairs within its rounding band of touching (pair_test.hpp's FloatBand)
// are tested again in double.
enum class Precision { kDouble, kFloat };

// How the detection finds a cell's particles (cell_index.hpp): a dense table with an entry per
// cell (the paper's; memory and the cell loop's iterations grow with the grid, at most 2^28
// keys), or a hash table over the occupied cells only (memory and iterations grow with N, for
// grids far larger than the particle count). kAuto chooses per scene (use_hashed_index in
// cell_grid.hpp); every choice gives the same contacts.
enum class GridIndex { kAuto, kDense, kHashed };

struct Schedule {
  ScheduleKind kind = ScheduleKind::kStatic;
  // Iterations per chunk. 0 only with static (plain block partition, one chunk per thread) and
  // always with balanced.
  int chunk = 0;
  friend bool operator==(const Schedule&, const Schedule&) = default;
};

struct Variant {
  LoopKind loop = LoopKind::kParticle;
  Order order = Order::kSorted;
  Stencil stencil = Stencil::kFull;
  Schedule schedule;
  Precision precision = Precision::kDouble;
  GridIndex grid = GridIndex::kAuto;
  friend bool operator==(const Variant&, const Variant&) = default;
};

std::string_view to_string(LoopKind loop);
std::string_view to_string(Order order);
std::string_view to_string(Stencil stencil);
std::string_view to_string(ScheduleKind kind);
std::string_view to_string(Precision precision);
std::string_view to_string(GridIndex index);
std::string to_string(const Schedule& schedule);  // "static", "static,200", "dynamic,4"
// Whether the chunk suits the kind: >= 0 with static (0: the block), 0 with balanced, >= 1
// with dynamic and guided.
bool has_valid_chunk(const Schedule& schedule);
std::string to_string(const Variant& variant);  // four parts, a fifth only for float

// Parsers throw InputError with a one-line message naming the bad part and the choices.
LoopKind parse_loop(std::string_view text);
Order parse_order(std::string_view text);
Stencil parse_stencil(std::string_view text);
Precision parse_precision(std::string_view text);
GridIndex parse_grid_index(std::string_view text);
Schedule parse_schedule(std::string_view text);  // "dynamic" alone means "dynamic,1"
Variant parse_variant(std::string_view text);

// One axis of the variant space: its name (the key of its named part), what it chooses, its
// values, and how it reads and writes its part of a Variant. Adding an axis = a field of
// Variant, an entry in the table, and (to enumerate it) a field of VariantSpace.
struct VariantAxis {
  std::string_view name;
  std::string_view help;
  std::vector<std::string_view> values;  // schedule: its kinds (a chunk may follow)
  std::string_view values_help;          // the values in words, for `contactlab variants`
  bool positional = false;               // one of the leading slash-separated parts
  void (*parse)(std::string_view text, Variant& into) = nullptr;
  std::string (*print)(const Variant& variant) = nullptr;
};
const std::vector<VariantAxis>& variant_axes();

// A rule between axes that every variant must keep (cf. AutoPas's
// Configuration::hasCompatibleValues): parse_variant rejects a variant that breaks one and
// enumerate() leaves it out. The detection axes are all compatible today; the DEM force
// accumulation axis will add "accumulate only with the half stencil".
struct VariantRule {
  std::string_view description;
  bool (*holds)(const Variant& variant) = nullptr;
};
const std::vector<VariantRule>& variant_rules();
// The description of the first rule `variant` breaks, or nothing.
std::optional<std::string_view> broken_rule(const Variant& variant);

// The axes, their values and the text form in words (the body of `contactlab variants`).
std::string variants_help();

// A grid of variants: the cartesian product of the listed choices.
struct VariantSpace {
  std::vector<LoopKind> loops;
  std::vector<Order> orders;
  std::vector<Stencil> stencils;
  std::vector<Schedule> schedules;
  std::vector<Precision> precisions{Precision::kDouble};
  std::vector<GridIndex> grids{GridIndex::kAuto};
};

// The product in the table's axis order, without the variants that break a rule.
std::vector<Variant> enumerate(const VariantSpace& space);

// The five configurations of Takagi et al. (Tables 2-5 and 7; chunk 200 for Table 7).
std::vector<Variant> paper_variants();

// Every loop, order, stencil, precision and grid index (dense and hashed; auto is one of them)
// with the schedules static, static,k, dynamic,k and guided,k for each k in `chunks`.
VariantSpace all_variants(const std::vector<int>& chunks);

}  // namespace contactlab
