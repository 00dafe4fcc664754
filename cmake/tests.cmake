# The C unit tests of the core, one ctest per case of test_core.c's case table.
add_executable(test_core "${CMAKE_SOURCE_DIR}/tests/fmu/core/test_core.c")
target_link_libraries(test_core PRIVATE sto_core)
file(STRINGS "${CMAKE_SOURCE_DIR}/tests/fmu/core/test_core.c" case_lines
     REGEX "^ *\\{\"[a-z_0-9]+\", [a-z_0-9]+\\},")
foreach(line IN LISTS case_lines)
    string(REGEX REPLACE "^ *\\{\"([a-z_0-9]+)\".*" "\\1" case "${line}")
    add_test(NAME core.${case} COMMAND test_core ${case})
endforeach()
# The case table is read at configure time: a new case reconfigures.
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
             "${CMAKE_SOURCE_DIR}/tests/fmu/core/test_core.c")
