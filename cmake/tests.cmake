# The C unit tests of the core: each program in tests/fmu/core/ (test_<name>.c) is
# built with the core library and run by ctest once per case of its case table.
file(GLOB test_sources "${CMAKE_SOURCE_DIR}/tests/fmu/core/test_*.c")
foreach(source IN LISTS test_sources)
    get_filename_component(program "${source}" NAME_WE)
    add_executable(${program} "${source}")
    target_link_libraries(${program} PRIVATE sto_core)
    file(STRINGS "${source}" case_lines REGEX "^ *\\{\"[a-z_0-9]+\", [a-z_0-9]+\\},")
    string(REGEX REPLACE "^test_" "" group "${program}")
    foreach(line IN LISTS case_lines)
        string(REGEX REPLACE "^ *\\{\"([a-z_0-9]+)\".*" "\\1" case "${line}")
        add_test(NAME ${group}.${case} COMMAND ${program} ${case})
    endforeach()
    # The case table is read at configure time: a new case reconfigures.
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${source}")
endforeach()
