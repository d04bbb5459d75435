# The table of STAC's libraries and programs in docs/architecture.md, made from the build's own
# targets so that it cannot drift: stac_write_target_table() (called at the end of the top-level
# CMakeLists.txt) writes build/architecture_targets.md, one row per library or program of the
# production folders, with its folder and what it links as declared (target_link_libraries).
# The test Docs.ArchitectureTableIsTheBuildsTargets compares it with the table between
# docs/architecture.md's markers; cmake/target_table.cmake puts it there (docs/architecture.md
# says how).

# Every target defined in `dir` and the folders below it.
function(stac_targets_under dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub ${subdirs})
    stac_targets_under(${sub} more)
    list(APPEND targets ${more})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

function(stac_write_target_table path)
  stac_targets_under(${PROJECT_SOURCE_DIR} targets)
  set(rows "")
  foreach(target ${targets})
    get_target_property(type ${target} TYPE)
    get_target_property(dir ${target} SOURCE_DIR)
    file(RELATIVE_PATH folder ${PROJECT_SOURCE_DIR} ${dir})
    if(NOT type MATCHES "^(STATIC_LIBRARY|EXECUTABLE)$" OR
       folder MATCHES "^(tests|benchmarks|fuzz|examples)(/|$)")
      continue()
    endif()
    get_target_property(links ${target} LINK_LIBRARIES)
    set(named "")
    if(links)
      foreach(link ${links})
        if(link MATCHES "^\\$<")
          continue()  # generator expressions (none today)
        endif()
        list(APPEND named "`${link}`")
      endforeach()
    endif()
    list(JOIN named ", " named_text)
    set(kind "")
    if(type STREQUAL "EXECUTABLE")
      set(kind " (program)")
    endif()
    list(APPEND rows "| `${target}`${kind} | `${folder}/` | ${named_text} |")
  endforeach()
  list(SORT rows)
  list(JOIN rows "\n" text)
  file(GENERATE OUTPUT ${path} CONTENT "| target | folder | links (as declared) |\n|---|---|---|\n${text}\n")
endfunction()
