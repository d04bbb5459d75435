# Writes the ROS 2 naming mode of idl/stac.idl (rmw_cyclonedds's convention, docs/dds.md):
# `module X { module msg {` gains `module dds_ {`, and every struct Name becomes Name_, at its
# declaration and at every use. Run at build time:
#   cmake -DIN=idl/stac.idl -DOUT=<build>/stac_ros2.idl -P idl/ros2_names.cmake
file(READ "${IN}" text)
string(REGEX MATCHALL "struct [A-Za-z0-9_]+" declared "${text}")
if(NOT declared)
  message(FATAL_ERROR "ros2_names: no struct in ${IN}")
endif()
string(REPLACE "module msg {" "module msg { module dds_ {" text "${text}")
string(REPLACE "}; };  // end module msg" "}; }; };  // end module msg" text "${text}")
string(REPLACE "::msg::" "::msg::dds_::" text "${text}")
foreach(decl IN LISTS declared)
  string(REPLACE "struct " "" name "${decl}")
  # The name followed by anything but an identifier character, preceded by a space, '<', ':' or
  # the line start (comments end up renamed too, which is harmless).
  string(REGEX REPLACE "([ <:\n])${name}([^A-Za-z0-9_])" "\\1${name}_\\2" text "${text}")
endforeach()
string(PREPEND text "// GENERATED from idl/stac.idl by idl/ros2_names.cmake: do not edit.\n")
file(WRITE "${OUT}.tmp" "${text}")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
