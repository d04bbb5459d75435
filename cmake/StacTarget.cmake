# One place for the language standard, warnings and sanitizers of every STAC target.
#   stac_target_defaults(<target>)
function(stac_target_defaults target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
                              -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual>
    $<$<COMPILE_LANGUAGE:C>:-Wall -Wextra>
    $<$<BOOL:${STAC_WERROR}>:-Werror>)
  if(STAC_SANITIZE STREQUAL "address")
    target_compile_options(${target} PUBLIC -fsanitize=address,undefined -fno-omit-frame-pointer
                                            -fno-sanitize-recover=undefined)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
    # GCC's flow analysis under the sanitizers' instrumentation reports libstdc++'s own
    # std::regex and std::function as maybe-uninitialized (false positives, GCC 12).
    target_compile_options(${target} PRIVATE $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
  elseif(STAC_SANITIZE STREQUAL "thread")
    target_compile_options(${target} PUBLIC -fsanitize=thread -fno-omit-frame-pointer)
    target_link_options(${target} PUBLIC -fsanitize=thread)
  elseif(NOT STAC_SANITIZE STREQUAL "")
    message(FATAL_ERROR "STAC_SANITIZE must be empty, 'address' or 'thread', not '${STAC_SANITIZE}'")
  endif()
endfunction()

# stac_add_library(<name> SOURCES ... [DEPS ...]): a static library whose include root is the
# repository root, so code includes "drivers/velodyne/packet.hpp".
function(stac_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  stac_target_defaults(${name})
endfunction()
