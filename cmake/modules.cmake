# The layering of docs/architecture.md, enforced by the build. Each module is one library whose include
# root (build/include/<root>/) holds nothing but links to what the module offers, so
# `#include "drivers/device.h"` resolves only in a target that links the Device seam (or a
# library that passes it on publicly). A module that includes what it may not use does not
# compile; tests/layering/ has a probe for every edge of the picture, and
# tools/check_layering.py states the finer rules (which module may include which, no OS header
# in analysis, config, control and gate) and fails the tests when one is broken.
#
#   hapticd_module(<target> <name> <folder> [ROOT <root> HEADERS ...]
#                  [SOURCES ...] [PUBLIC ...] [PRIVATE ...])
#     A static library of SOURCES (an interface library without them) whose headers are
#     included as "<name>/file.h"; PUBLIC libraries are part of its interface, PRIVATE only of
#     its implementation. Every module stands on the floor, hapticd_base (src/base/).
#     Without HEADERS the whole of <folder> is reachable (root build/include/<name>/). With
#     them only those headers of <folder> are, from their own root build/include/<root>/: a
#     seam (drivers/device.h alone) or a driver's pure codecs, without the rest of the folder.
function(hapticd_module target name folder)
  cmake_parse_arguments(M "" "ROOT" "HEADERS;SOURCES;PUBLIC;PRIVATE" ${ARGN})
  if(NOT target STREQUAL hapticd_base)
    list(APPEND M_PUBLIC hapticd_base)
  endif()
  if(M_HEADERS)
    set(root ${PROJECT_BINARY_DIR}/include/${M_ROOT})
    file(REMOVE_RECURSE ${root})  # a header taken off the list must not stay reachable
    foreach(header ${M_HEADERS})
      set(link ${root}/${name}/${header})
      get_filename_component(dir ${link} DIRECTORY)
      file(MAKE_DIRECTORY ${dir})
      file(CREATE_LINK ${folder}/${header} ${link} SYMBOLIC)
    endforeach()
  else()
    set(root ${PROJECT_BINARY_DIR}/include/${name})
    if(NOT EXISTS ${root}/${name})
      file(MAKE_DIRECTORY ${root})
      file(CREATE_LINK ${folder} ${root}/${name} SYMBOLIC)
    endif()
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
