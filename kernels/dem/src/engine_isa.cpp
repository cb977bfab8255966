// The DEM step's hot loops (Engine::compute_forces and advance's drift, with the kernels of
// force_pass, pair_block, kin_columns, particle_update and wall_law) compiled once per x86
// instruction set, and the choice among them (dem_isa.hpp says how).
//
// Everything these headers include is included here first, outside any target region: a
// standard or project function first defined inside one would carry its instruction set, and
// the linker could keep that copy for the whole program.
#include <fmt/core.h>
#include <omp.h>
#include <unistd.h>  // pair_block.hpp: sysconf
#if defined(__x86_64__)
#include <immintrin.h>  // lanes.hpp: the square roots
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "contactlab/dem/contact_law.hpp"
#include "contactlab/dem/engine.hpp"
#include "contactlab/dem/force_variant.hpp"
#include "contactlab/dem/pair_list.hpp"
#include "contactlab/dem/particles.hpp"
#include "contactlab/dem/walls.hpp"
#include "contactlab/kernels/simd.hpp"

namespace contactlab::dem {

std::string to_string(StepIsa isa) {
  switch (isa) {
    case StepIsa::kAvx512:
      return "AVX-512";
    case StepIsa::kAvx2:
      return "AVX2";
    case StepIsa::kBaseline:
      break;
  }
  return "baseline";
}

StepIsa step_isa() {
#if defined(__x86_64__)
  // simd_target() is one the CPU runs (Highway's check of the CPU's features and the OS's
  // saving of their registers); Highway's AVX3 needs AVX-512 F, VL, DQ, BW and CD, as below.
  const std::string target = simd_target();
  if (target.starts_with("AVX3")) return StepIsa::kAvx512;
  if (target == "AVX2") return StepIsa::kAvx2;
#endif
  return StepIsa::kBaseline;
}

}  // namespace contactlab::dem

// The target regions: GCC's pragmas. Clang (clang-tidy reads this file) has its own form; there
// the passes are checked without one, which is all a check needs.
#if defined(__clang__)
#define CONTACTLAB_TARGET_PUSH(spec)
#define CONTACTLAB_TARGET_POP()
#else
#define CONTACTLAB_PRAGMA(text) _Pragma(#text)
#define CONTACTLAB_TARGET_PUSH(spec) _Pragma("GCC push_options") CONTACTLAB_PRAGMA(GCC target(spec))
#define CONTACTLAB_TARGET_POP() _Pragma("GCC pop_options")
#endif

#if defined(__x86_64__)
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace avx512
#define CONTACTLAB_DEM_ISA_NS avx512
#define CONTACTLAB_DEM_ISA_ID StepIsa::kAvx512
#define CONTACTLAB_DEM_LANE_PARTS 1  // eight doubles a register (lanes.hpp)
CONTACTLAB_TARGET_PUSH(
    "avx512f,avx512vl,avx512dq,avx512bw,avx512cd,avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c")
#include "engine_step.inc"
CONTACTLAB_TARGET_POP()
#undef CONTACTLAB_DEM_ISA_NAMESPACE
#undef CONTACTLAB_DEM_ISA_NS
#undef CONTACTLAB_DEM_ISA_ID
#undef CONTACTLAB_DEM_LANE_PARTS

#define CONTACTLAB_DEM_ISA_TOGGLE  // the headers once more
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace avx2
#define CONTACTLAB_DEM_ISA_NS avx2
#define CONTACTLAB_DEM_ISA_ID StepIsa::kAvx2
#define CONTACTLAB_DEM_LANE_PARTS 2  // four
CONTACTLAB_TARGET_PUSH("no-avx512f,avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c")
#include "engine_step.inc"
CONTACTLAB_TARGET_POP()
#undef CONTACTLAB_DEM_ISA_NAMESPACE
#undef CONTACTLAB_DEM_ISA_NS
#undef CONTACTLAB_DEM_ISA_ID
#undef CONTACTLAB_DEM_LANE_PARTS

#undef CONTACTLAB_DEM_ISA_TOGGLE  // and once more
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace baseline
#define CONTACTLAB_DEM_ISA_NS baseline
#define CONTACTLAB_DEM_ISA_ID StepIsa::kBaseline
#define CONTACTLAB_DEM_LANE_PARTS 4  // two
CONTACTLAB_TARGET_PUSH("no-avx")
#include "engine_step.inc"
CONTACTLAB_TARGET_POP()

#else  // one set: the build's
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) namespace baseline
#define CONTACTLAB_DEM_ISA_NS baseline
#define CONTACTLAB_DEM_ISA_ID StepIsa::kBaseline
#include "engine_step.inc"
namespace contactlab::dem {
// Where there is one set, the others are it.
template <>
void Engine::compute_forces_on<StepIsa::kAvx2>(bool final_kick, bool drift_next) {
  compute_forces_on<StepIsa::kBaseline>(final_kick, drift_next);
}
template <>
void Engine::compute_forces_on<StepIsa::kAvx512>(bool final_kick, bool drift_next) {
  compute_forces_on<StepIsa::kBaseline>(final_kick, drift_next);
}
template <>
void Engine::drift_on<StepIsa::kAvx2>(double& max_disp_sq, double& max_step_sq,
                                      std::uint32_t& bad) {
  drift_on<StepIsa::kBaseline>(max_disp_sq, max_step_sq, bad);
}
template <>
void Engine::drift_on<StepIsa::kAvx512>(double& max_disp_sq, double& max_step_sq,
                                        std::uint32_t& bad) {
  drift_on<StepIsa::kBaseline>(max_disp_sq, max_step_sq, bad);
}
}  // namespace contactlab::dem
#endif
