# Lays out and zips one FMU (run by `cmake -P` from the FMU's build rule):
#   - modelDescription.xml from the model's C variable table (describe_model), which
#     must equal the committed one: the C table is the single source of truth;
#   - sources/ with the model's C files, the shipped headers and buildDescription.xml,
#     so that an importer (fmpy compile) can rebuild the binary;
#   - the binary the build put in binaries/<platform>/, whose exports are checked;
#   - the zip.
# Variables: DESCRIBE FMI_VERSION LAYOUT COMMITTED_XML SOURCE_ROOT SOURCES (;-list,
# relative to SOURCE_ROOT) HEADERS (;-list) BINARY FMU NM (empty: no export check)
# RESOURCES (;-list of files for resources/, may be empty).
foreach(var DESCRIBE FMI_VERSION LAYOUT COMMITTED_XML SOURCE_ROOT SOURCES BINARY FMU)
    if(NOT DEFINED ${var})
        message(FATAL_ERROR "package_fmu.cmake: ${var} is not set")
    endif()
endforeach()
string(REPLACE "," ";" SOURCES "${SOURCES}")
string(REPLACE "," ";" HEADERS "${HEADERS}")
string(REPLACE "," ";" RESOURCES "${RESOURCES}")

execute_process(COMMAND "${DESCRIBE}" "fmi${FMI_VERSION}" ${SOURCES}
                OUTPUT_FILE "${LAYOUT}/modelDescription.xml" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
    message(FATAL_ERROR "describe_model failed for ${LAYOUT} (${status})")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${COMMITTED_XML}"
                        "${LAYOUT}/modelDescription.xml" RESULT_VARIABLE differs)
if(differs)
    execute_process(COMMAND diff -u "${COMMITTED_XML}" "${LAYOUT}/modelDescription.xml")
    message(FATAL_ERROR "${COMMITTED_XML} is out of date with the model's variable table.\n"
            "Regenerate it: cp ${LAYOUT}/modelDescription.xml ${COMMITTED_XML}")
endif()

file(REMOVE_RECURSE "${LAYOUT}/sources")
foreach(file IN LISTS SOURCES HEADERS)
    get_filename_component(folder "${file}" DIRECTORY)
    file(COPY "${SOURCE_ROOT}/${file}" DESTINATION "${LAYOUT}/sources/${folder}")
endforeach()
execute_process(COMMAND "${DESCRIBE}" build ${SOURCES}
                OUTPUT_FILE "${LAYOUT}/sources/buildDescription.xml" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
    message(FATAL_ERROR "describe_model build failed for ${LAYOUT} (${status})")
endif()

file(REMOVE_RECURSE "${LAYOUT}/resources")
foreach(file IN LISTS RESOURCES)
    file(COPY "${file}" DESTINATION "${LAYOUT}/resources")
endforeach()

# Only the FMI functions of the FMU's version may be exported.
if(NM)
    execute_process(COMMAND "${NM}" -D --defined-only "${BINARY}" OUTPUT_VARIABLE symbols
                    RESULT_VARIABLE status)
    if(NOT status EQUAL 0)
        message(FATAL_ERROR "${NM} could not read ${BINARY}")
    endif()
    string(REGEX MATCHALL "[^\n]+" lines "${symbols}")
    foreach(line IN LISTS lines)
        string(REGEX REPLACE "^.* " "" name "${line}")
        if(NOT name MATCHES "^fmi${FMI_VERSION}")
            message(FATAL_ERROR "${BINARY} exports a non-FMI symbol: ${name}")
        endif()
    endforeach()
endif()

# Members in a fixed order with a fixed time stamp: the same sources give the same zip.
set(members modelDescription.xml)
foreach(folder binaries sources documentation resources)
    file(GLOB_RECURSE found RELATIVE "${LAYOUT}" "${LAYOUT}/${folder}/*")
    list(SORT found)
    list(APPEND members ${found})
endforeach()
get_filename_component(fmu_dir "${FMU}" DIRECTORY)
file(MAKE_DIRECTORY "${fmu_dir}")
file(REMOVE "${FMU}.partial")
execute_process(COMMAND "${CMAKE_COMMAND}" -E tar cf "${FMU}.partial" --format=zip
                        "--mtime=2000-01-01 00:00:00 UTC" -- ${members}
                WORKING_DIRECTORY "${LAYOUT}" RESULT_VARIABLE status)
if(NOT status EQUAL 0)
    file(REMOVE "${FMU}.partial")
    message(FATAL_ERROR "zipping ${LAYOUT} into ${FMU} failed")
endif()
file(RENAME "${FMU}.partial" "${FMU}")
