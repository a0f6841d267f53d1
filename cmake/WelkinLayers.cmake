# SPDX-License-Identifier: Apache-2.0
# welkin_layer(NAME [DEPENDENCIES...]) makes the static library welkin_NAME from
# src/NAME/*.cpp, with the public headers in include/welkin/NAME/, linked publicly to the
# layers it builds on. welkin_check_layers() then reads every #include "welkin/X/..." in
# those folders and fails the configure step when X is neither the layer itself nor one
# it depends on, directly or through its dependencies.

# Warnings for every target of the project; WELKIN_WERROR makes them errors.
set(WELKIN_WARNINGS -Wall -Wextra)
if(WELKIN_WERROR)
  list(APPEND WELKIN_WARNINGS -Werror)
endif()

function(welkin_layer name)
  set(deps ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cpp)
  add_library(welkin_${name} STATIC ${sources})
  target_include_directories(welkin_${name} PUBLIC ${PROJECT_SOURCE_DIR}/include)
  foreach(dep IN LISTS deps)
    target_link_libraries(welkin_${name} PUBLIC welkin_${dep})
  endforeach()
  # The LUT builds' inner loops run over many texels or sun angles at once; GCC turns them
  # into SIMD code only when std::sqrt need not set errno and a select of two computed
  # values may be made unconditionally (nothing here reads errno or traps on FP
  # exceptions). Neither flag changes a result: IEEE arithmetic is kept (no -ffast-math).
  # No fused multiply-adds either (-ffp-contract=off): the AVX-512 build of those loops
  # (base/simd.hpp) could otherwise contract a * b + c, and every build of a loop must
  # give the same bits.
  target_compile_options(welkin_${name} PRIVATE ${WELKIN_WARNINGS}
    -fno-math-errno -fno-trapping-math -ffp-contract=off)
  # Transitive closure of the dependencies, for the layering check.
  set(closure ${name})
  foreach(dep IN LISTS deps)
    get_property(dep_closure GLOBAL PROPERTY WELKIN_LAYER_CLOSURE_${dep})
    if(NOT DEFINED dep_closure OR dep_closure STREQUAL "")
      message(FATAL_ERROR "welkin_layer(${name}): layer '${dep}' must be declared before it")
    endif()
    list(APPEND closure ${dep_closure})
  endforeach()
  list(REMOVE_DUPLICATES closure)
  set_property(GLOBAL PROPERTY WELKIN_LAYER_CLOSURE_${name} "${closure}")
  set_property(GLOBAL APPEND PROPERTY WELKIN_LAYERS ${name})
endfunction()

function(welkin_check_layers)
  get_property(layers GLOBAL PROPERTY WELKIN_LAYERS)
  set(errors "")
  foreach(name IN LISTS layers)
    get_property(allowed GLOBAL PROPERTY WELKIN_LAYER_CLOSURE_${name})
    file(GLOB files CONFIGURE_DEPENDS
      ${PROJECT_SOURCE_DIR}/include/welkin/${name}/*.hpp ${PROJECT_SOURCE_DIR}/src/${name}/*.cpp)
    foreach(file IN LISTS files)
      file(STRINGS ${file} includes REGEX "^#include [<\"]welkin/")
      foreach(line IN LISTS includes)
        if(line MATCHES "^#include [<\"]welkin/([a-z_0-9]+)/")
          set(used ${CMAKE_MATCH_1})
          if(NOT used IN_LIST layers)
            string(APPEND errors "\n  ${file}: '${line}' names no layer")
          elseif(NOT used IN_LIST allowed)
            string(APPEND errors "\n  ${file}: layer '${name}' includes '${used}', which it does not depend on")
          endif()
        else()
          string(APPEND errors "\n  ${file}: '${line}' is outside every layer's folder")
        endif()
      endforeach()
    endforeach()
  endforeach()
  if(errors)
    message(FATAL_ERROR "Welkin's layering is broken (docs/design.md, 'Layout'):${errors}")
  endif()
  # The layers in the order declared (each after those it builds on), one per line, for
  # the tools that link the static libraries themselves (scripts/fuzz.sh).
  list(JOIN layers "\n" lines)
  file(WRITE ${CMAKE_BINARY_DIR}/welkin_layers.txt "${lines}\n")
endfunction()
