# The project's own code builds warning-free. HAPTICD_WERROR makes warnings errors: the quick
# start and CI turn it on; a packager's plain build leaves it off, so a newer compiler's new
# warning does not stop a build that works. Third-party headers come in as SYSTEM includes
# through their imported targets, so their warnings never count.
option(HAPTICD_WERROR "Treat the project's compiler warnings as errors (quick start and CI)" OFF)
add_library(hapticd_warnings INTERFACE)
target_compile_options(hapticd_warnings INTERFACE
  -Wall -Wextra -Wpedantic
  -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough
  $<$<BOOL:${HAPTICD_WERROR}>:-Werror>)

# GCC 12 at -O3 reports impossible overlaps in inlined std::string copies ("accessing
# 9223372036854775810 or more bytes", GCC bug 105329, fixed in GCC 13): a false positive of
# the library headers that moves with every inlining change, so it is off for GCC 12 only.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(hapticd_warnings INTERFACE -Wno-restrict)
endif()
