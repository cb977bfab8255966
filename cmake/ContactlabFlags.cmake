# Compiler flags shared by every contactlab target, collected in contactlab::flags.
add_library(contactlab_flags INTERFACE)
add_library(contactlab::flags ALIAS contactlab_flags)
target_compile_options(contactlab_flags INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                                  -Wno-sign-conversion
                                                  # Contact sets must be bit-identical between the
                                                  # kernels, the brute force and other machines:
                                                  # no fused multiply-add contraction.
                                                  -ffp-contract=off)
if(CONTACTLAB_WERROR)
  target_compile_options(contactlab_flags INTERFACE -Werror)
endif()
set(CONTACTLAB_ARCH_FLAGS "")
if(CONTACTLAB_NATIVE)
  set(CONTACTLAB_ARCH_FLAGS "-march=native")
  target_compile_options(contactlab_flags INTERFACE -march=native)
endif()
if(CONTACTLAB_SANITIZE)
  target_compile_options(contactlab_flags INTERFACE -fsanitize=${CONTACTLAB_SANITIZE} -fno-omit-frame-pointer)
  target_link_options(contactlab_flags INTERFACE -fsanitize=${CONTACTLAB_SANITIZE})
endif()
