# Included by the top-level CMakeLists.txt when HAPTICD_FUZZ=ON, before any project library is
# defined: the whole build is instrumented for libFuzzer's coverage feedback and for ASan and
# UBSan, so every library a fuzz target links is both explored and checked. The fuzz targets
# alone link libFuzzer's main (fuzz/CMakeLists.txt).
if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  message(FATAL_ERROR
    "HAPTICD_FUZZ=ON needs clang (libFuzzer ships with it), but CMAKE_CXX_COMPILER is "
    "${CMAKE_CXX_COMPILER_ID} (${CMAKE_CXX_COMPILER}). Use a separate build directory: "
    "CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DHAPTICD_FUZZ=ON "
    "-DHAPTICD_BUILD_TESTS=OFF -DHAPTICD_BUILD_BENCHMARKS=OFF, or simply tools/fuzz.sh build")
endif()

include(CheckCXXSourceCompiles)
set(CMAKE_REQUIRED_FLAGS -fsanitize=fuzzer)
set(CMAKE_REQUIRED_LINK_OPTIONS -fsanitize=fuzzer)
check_cxx_source_compiles(
  "#include <cstddef>
   #include <cstdint>
   extern \"C\" int LLVMFuzzerTestOneInput(const std::uint8_t*, std::size_t) { return 0; }"
  HAPTICD_HAVE_LIBFUZZER)
unset(CMAKE_REQUIRED_FLAGS)
unset(CMAKE_REQUIRED_LINK_OPTIONS)
if(NOT HAPTICD_HAVE_LIBFUZZER)
  message(FATAL_ERROR
    "HAPTICD_FUZZ=ON: ${CMAKE_CXX_COMPILER} cannot link -fsanitize=fuzzer; install the "
    "libclang-rt-N-dev of its clang-N (tools/quickstart.sh packages installs it)")
endif()

# Any UBSan report aborts, so libFuzzer records it as a crash instead of printing and going on.
add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                    -fno-omit-frame-pointer)
add_link_options(-fsanitize=address,undefined)
# The analysis is floating-point numerics over frequency grids: tracing its comparisons tells
# the fuzzer nothing about the input's structure and took half of each gate evaluation.
add_compile_options(
  $<$<STREQUAL:$<TARGET_PROPERTY:NAME>,hapticd_analysis>:-fno-sanitize-coverage=trace-cmp>)
