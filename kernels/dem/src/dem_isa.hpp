// The instruction sets the DEM step's hot loops are compiled for (private to src/).
//
// The force pass, the particles' finish and their drift are written once, in the headers that
// include this one (kin_columns, pair_block, force_pass, particle_update, wall_law). Included
// the usual way (engine.cpp, the tests) they compile with the build's flags, in the inline
// namespace `build`. engine_isa.cpp includes them once per x86 instruction set, each time under
// `#pragma GCC target` and in a namespace of its own (avx3, avx2, sse), which a toggle lets
// them be included again for (no include guard: as Highway's foreach_target). So one portable
// binary runs the step on the best vectors the CPU has: the pair law's eight-lane GCC vectors
// are one AVX-512 register there, and a portable -march=x86-64-v3 build had run the bed's step
// 2.5 - 2.8x slower than the native one (issue #48).
#pragma once

// The namespace the headers' kernels are defined in: `build` by default (inline, so that
// detail::name finds them), engine_isa.cpp's own per pass.
#ifndef CONTACTLAB_DEM_ISA_NAMESPACE
#define CONTACTLAB_DEM_ISA_NAMESPACE(name) inline namespace name
#endif
