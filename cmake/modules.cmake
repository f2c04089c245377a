# The layering of docs/architecture.md, enforced by the build. Each module is one library whose include
# root (build/include/<name>/) holds nothing but a link to the module's own folder, so
# `#include "drivers/device.h"` resolves only in a target that links the drivers' library (or a
# library that passes it on publicly). A module that includes what it may not use does not
# compile; tools/check_layering.py states the finer rules (which module may include which, no
# OS header in analysis, control and gate) and fails the tests when one is broken.
#
#   hapticd_module(<target> <name> <folder> [SOURCES ...] [PUBLIC ...] [PRIVATE ...])
#     A static library of SOURCES (an interface library without them) whose headers are
#     included as "<name>/file.h"; PUBLIC libraries are part of its interface, PRIVATE only of
#     its implementation. Every module stands on the floor, hapticd_base (src/base/).
function(hapticd_module target name folder)
  cmake_parse_arguments(M "" "" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  if(NOT target STREQUAL hapticd_base)
    list(APPEND M_PUBLIC hapticd_base)
  endif()
  set(root ${PROJECT_BINARY_DIR}/include/${name})
  if(NOT EXISTS ${root}/${name})
    file(MAKE_DIRECTORY ${root})
    file(CREATE_LINK ${folder} ${root}/${name} SYMBOLIC)
  endif()
  if(M_SOURCES)
    add_library(${target} STATIC ${M_SOURCES})
    target_include_directories(${target} PUBLIC ${root})
    target_link_libraries(${target} PUBLIC ${M_PUBLIC} PRIVATE hapticd_warnings ${M_PRIVATE})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${root})
    target_link_libraries(${target} INTERFACE ${M_PUBLIC})
  endif()
endfunction()
