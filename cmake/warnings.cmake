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
