# Compiler flags shared by every contactlab target, collected in contactlab::flags.
add_library(contactlab_flags INTERFACE)
add_library(contactlab::flags ALIAS contactlab_flags)
target_compile_options(contactlab_flags INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                                  -Wno-sign-conversion
                                                  # Contact sets must be bit-identical between the
                                                  # kernels, the brute force and other machines:
                                                  # no fused multiply-add contraction.
                                                  -ffp-contract=off
                                                  # Without AVX-512, GCC notes that the DEM
                                                  # kernels' 64-byte vectors are passed in
                                                  # memory: that matters only between objects
                                                  # built with other flags, never here.
                                                  -Wno-psabi)
if(CONTACTLAB_WERROR)
  target_compile_options(contactlab_flags INTERFACE -Werror)
endif()
set(CONTACTLAB_ARCH_FLAGS "")
# The cache simulator's program (apps/contactlab-cachesim) runs under valgrind, which cannot
# execute AVX-512: it is compiled for the native CPU with AVX-512 switched off (-mno-avx512f
# switches off every AVX-512 extension and wins over -march=native whatever their order).
set(CONTACTLAB_CACHESIM_ARCH_FLAGS "")
set(CONTACTLAB_CACHESIM_ISA "x86-64 as the compiler's default target (-march not given)")
if(CONTACTLAB_NATIVE)
  set(CONTACTLAB_ARCH_FLAGS "-march=native")
  target_compile_options(contactlab_flags INTERFACE -march=native)
  set(CONTACTLAB_CACHESIM_ARCH_FLAGS -mno-avx512f)
  set(CONTACTLAB_CACHESIM_ISA "the native CPU without AVX-512 (-march=native -mno-avx512f)")
endif()
if(CONTACTLAB_SANITIZE)
  target_compile_options(contactlab_flags INTERFACE -fsanitize=${CONTACTLAB_SANITIZE} -fno-omit-frame-pointer)
  target_link_options(contactlab_flags INTERFACE -fsanitize=${CONTACTLAB_SANITIZE})
endif()
