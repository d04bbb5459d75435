# Runs idlc on one IDL file with no path of this machine in what it writes (cmake -P; idl/CMakeLists.txt).
# idlc names its input's absolute path in each output's header comment and the output's path in the
# include guard: the generated stac.h would then differ between two clones at different paths, and
# every file including it would miss ccache. So the IDL is copied beside the outputs, idlc runs
# there on the bare file name, and the "Source:" line is made relative.
#   -DIDLC=idlc -DIN=/abs/name.idl -DOUT_DIR=/abs/dir -DEXTENSIBILITY=final
get_filename_component(name ${IN} NAME)
get_filename_component(stem ${IN} NAME_WE)
if(NOT IN STREQUAL "${OUT_DIR}/${name}")
  configure_file(${IN} ${OUT_DIR}/${name} COPYONLY)
endif()
execute_process(COMMAND ${IDLC} -x ${EXTENSIBILITY} ${name} WORKING_DIRECTORY ${OUT_DIR}
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "idlc failed on ${IN}: ${result}")
endif()
foreach(suffix .c .h)
  file(READ ${OUT_DIR}/${stem}${suffix} text)
  string(REPLACE "Source: ${OUT_DIR}/${name}" "Source: ${name}" text "${text}")
  file(WRITE ${OUT_DIR}/${stem}${suffix} "${text}")
endforeach()
