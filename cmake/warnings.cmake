# Warnings are errors for the project's own code. Third-party headers come in as SYSTEM
# includes through their imported targets, so their warnings do not stop the build.
add_library(hapticd_warnings INTERFACE)
target_compile_options(hapticd_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Werror
  -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
  -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough)
