// The instruction set the contact tests of the sorted layouts run on. The pair test of
// pair_test.hpp is written once on SIMD lanes with Highway (libhwy) and compiled for every
// x86 target Highway attains ("AVX3_DL" and "AVX3" = AVX-512, "AVX2", "SSE4", "SSSE3", and its
// portable path, "EMU128" or "SCALAR"); at run time the best one the CPU has is used (dynamic
// dispatch). "off" runs the scalar per-candidate loop of the traversal instead. The unsorted
// layouts and the DEM neighbour list always use the scalar loop. Every path makes the same decision
// with the same arithmetic (no fused multiply-add, <= on squared distances): bit-identical lists.
//
// The choice is process-wide: CONTACTLAB_SIMD=<name> in the environment sets it at the first
// detection, select_simd_target() at any time (tests, a command's option).
// The DEM step follows it too (contactlab/dem/engine.hpp, StepIsa): AVX3... runs its AVX-512
// code, AVX2 its AVX2 code, anything else its baseline code.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace contactlab {

// "off", or the Highway target in use ("AVX3", "AVX2", ...).
std::string simd_target();

// The targets this CPU runs and this build holds, best first, then "off".
std::vector<std::string> simd_targets();

// Uses `name` (one of simd_targets(), case-insensitive) from now on; "best" = the best the CPU
// has. Throws InputError naming the choices for anything else.
void select_simd_target(std::string_view name);

// Whether the contact tests of the sorted layouts run on SIMD lanes (simd_target() != "off").
bool simd_enabled();

// Whether a target was named (select_simd_target or CONTACTLAB_SIMD other than "best"): then
// every home of the sorted layouts runs on it. Otherwise the detector keeps sparse scenes and
// homes with few candidates in the scalar loop, where a vector call costs more than the tests.
bool simd_forced();

}  // namespace contactlab
