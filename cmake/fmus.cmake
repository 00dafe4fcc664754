# The FMUs: one shared library per model and FMI version (the FMI API file, the
# model, the instance core and the algorithm core), laid out, checked and zipped
# by cmake/package_fmu.cmake when the host can run the describe tool.

# Platform folders: FMI 2 names (empty: FMI 2 has none) and FMI 3 tuples.  A cross
# toolchain file sets them; the host build derives them.
if(NOT DEFINED STO_FMI3_PLATFORM)
    if(CMAKE_SYSTEM_NAME STREQUAL "Linux" AND CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
        set(STO_FMI2_PLATFORM linux64)
        set(STO_FMI3_PLATFORM x86_64-linux)
    elseif(CMAKE_SYSTEM_NAME STREQUAL "Linux" AND CMAKE_SYSTEM_PROCESSOR MATCHES "aarch64|arm64")
        set(STO_FMI2_PLATFORM "")
        set(STO_FMI3_PLATFORM aarch64-linux)
    else()
        message(FATAL_ERROR "Unknown FMU platform for ${CMAKE_SYSTEM_NAME} ${CMAKE_SYSTEM_PROCESSOR}: "
                            "use a toolchain file of cmake/toolchains/")
    endif()
endif()
if(WIN32)
    set(STO_FMU_SUFFIX .dll)
elseif(APPLE)
    set(STO_FMU_SUFFIX .dylib)
else()
    set(STO_FMU_SUFFIX .so)
endif()
find_program(STO_NM NAMES nm)

file(GLOB STO_CORE_HEADERS RELATIVE "${SRC}" CONFIGURE_DEPENDS "${SRC}/core/*.h")
set(STO_ALL_FMUS "")
set(STO_FMI2_FMUS "")

function(sto_fmu_paths id fmi layout_var fmu_var)
    if(fmi EQUAL 2)
        set(${layout_var} "${STO_OUTPUT_DIR}/${id}" PARENT_SCOPE)
        set(${fmu_var} "${STO_OUTPUT_DIR}/fmus/${id}.fmu" PARENT_SCOPE)
    else()
        set(${layout_var} "${STO_OUTPUT_DIR}/fmi3/${id}" PARENT_SCOPE)
        set(${fmu_var} "${STO_OUTPUT_DIR}/fmi3/${id}.fmu" PARENT_SCOPE)
    endif()
endfunction()

# The FMU's sources relative to fmu/src, as shipped: API file, instance core, model, core.
function(sto_fmu_sources id fmi out_var)
    set(${out_var} fmi${fmi}/fmi${fmi}_functions.c ${STO_INSTANCE_SOURCES}
        ${STO_${id}_MODEL} ${STO_${id}_CORE} PARENT_SCOPE)
endfunction()

function(sto_add_fmu id fmi)
    if(fmi EQUAL 2)
        set(platform "${STO_FMI2_PLATFORM}")
    else()
        set(platform "${STO_FMI3_PLATFORM}")
    endif()
    if(platform STREQUAL "")
        return()
    endif()
    sto_fmu_paths(${id} ${fmi} layout fmu)
    set(target ${id}_fmi${fmi})
    # A module: loaded by importers, never linked against (Mach-O: a dylib, as importers expect).
    if(APPLE)
        add_library(${target} SHARED)
    else()
        add_library(${target} MODULE)
    endif()
    target_sources(${target} PRIVATE "${SRC}/fmi${fmi}/fmi${fmi}_functions.c" "${SRC}/${STO_${id}_MODEL}")
    target_include_directories(${target} SYSTEM PRIVATE "${STO_FMI_INCLUDE_DIR}")
    target_link_libraries(${target} PRIVATE sto_instance sto_core)
    set_target_properties(${target} PROPERTIES
        OUTPUT_NAME ${id} PREFIX "" SUFFIX ${STO_FMU_SUFFIX}
        LIBRARY_OUTPUT_DIRECTORY "${layout}/binaries/${platform}"
        RUNTIME_OUTPUT_DIRECTORY "${layout}/binaries/${platform}"
        ARCHIVE_OUTPUT_DIRECTORY "${CMAKE_BINARY_DIR}/import/${target}")
    if(NOT STO_PACKAGE_FMUS)
        return()
    endif()

    sto_fmu_sources(${id} ${fmi} sources)
    set(committed "${CMAKE_SOURCE_DIR}/${STO_${id}_XML_DIR}/modelDescription.xml")
    if(fmi EQUAL 3)
        set(committed "${CMAKE_SOURCE_DIR}/${STO_${id}_XML_DIR}/fmi3/modelDescription.xml")
    endif()
    set(headers ${STO_SHIPPED_HEADERS} ${STO_CORE_HEADERS})
    list(TRANSFORM sources PREPEND "${SRC}/" OUTPUT_VARIABLE source_paths)
    list(TRANSFORM headers PREPEND "${SRC}/" OUTPUT_VARIABLE header_paths)
    string(REPLACE ";" "," source_list "${sources}")
    string(REPLACE ";" "," header_list "${headers}")
    list(TRANSFORM STO_${id}_RESOURCES PREPEND "${CMAKE_SOURCE_DIR}/" OUTPUT_VARIABLE resources)
    string(REPLACE ";" "," resource_list "${resources}")
    set(nm "")
    if(CMAKE_SYSTEM_NAME STREQUAL "Linux" AND STO_NM)
        set(nm "${STO_NM}")
    endif()
    set(commands COMMAND "${CMAKE_COMMAND}"
        "-DDESCRIBE=$<TARGET_FILE:describe_${id}>" -DFMI_VERSION=${fmi} "-DLAYOUT=${layout}"
        "-DCOMMITTED_XML=${committed}" "-DSOURCE_ROOT=${SRC}" "-DSOURCES=${source_list}"
        "-DHEADERS=${header_list}" "-DBINARY=$<TARGET_FILE:${target}>" "-DFMU=${fmu}" "-DNM=${nm}"
        "-DRESOURCES=${resource_list}"
        -P "${CMAKE_SOURCE_DIR}/cmake/package_fmu.cmake")
    if(STO_CHECK_FMUS)
        # The FMU's default experiment as its reference result (FMI-LS-REF), embedded.
        list(APPEND commands COMMAND "${STO_PYTHON}" tools/importers/make_reference.py "${fmu}")
    endif()
    add_custom_command(OUTPUT "${fmu}" ${commands}
        DEPENDS ${target} describe_${id} "${committed}" ${source_paths} ${header_paths} ${resources}
                "${CMAKE_SOURCE_DIR}/cmake/package_fmu.cmake" "${CMAKE_SOURCE_DIR}/tools/importers/make_reference.py"
        WORKING_DIRECTORY "${CMAKE_SOURCE_DIR}"
        COMMENT "Packaging ${id}.fmu (FMI ${fmi})" VERBATIM)
    add_custom_target(${target}_fmu ALL DEPENDS "${fmu}")
    set(STO_ALL_FMUS ${STO_ALL_FMUS} "${fmu}" PARENT_SCOPE)
    if(fmi EQUAL 2)
        set(STO_FMI2_FMUS ${STO_FMI2_FMUS} "${fmu}" PARENT_SCOPE)
    endif()
endfunction()

if(STO_FMUS)
    foreach(id IN LISTS STO_MODELS)
        if(STO_PACKAGE_FMUS)
            # Prints the model's descriptions from its C variable table (host tool).
            add_executable(describe_${id} "${CMAKE_SOURCE_DIR}/fmu/tools/describe_model.c"
                           "${SRC}/${STO_${id}_MODEL}")
            target_link_libraries(describe_${id} PRIVATE sto_core)
        endif()
        sto_add_fmu(${id} 2)
        sto_add_fmu(${id} 3)
    endforeach()
    if(STO_CHECK_FMUS AND STO_PACKAGE_FMUS)
        set(stamp "${CMAKE_BINARY_DIR}/fmus-validated.stamp")
        add_custom_command(OUTPUT "${stamp}"
            COMMAND "${STO_PYTHON}" -m harness.package --validate ${STO_ALL_FMUS}
            COMMAND "${CMAKE_COMMAND}" -E touch "${stamp}"
            DEPENDS ${STO_ALL_FMUS} WORKING_DIRECTORY "${CMAKE_SOURCE_DIR}"
            COMMENT "Validating the FMUs with fmpy" VERBATIM)
        set(ssp "${STO_OUTPUT_DIR}/ClosedLoop.ssp")
        add_custom_command(OUTPUT "${ssp}"
            COMMAND "${STO_PYTHON}" -m harness.ssp "${STO_OUTPUT_DIR}/fmus" "${ssp}"
            DEPENDS ${STO_FMI2_FMUS} "${CMAKE_SOURCE_DIR}/harness/ssp.py"
            WORKING_DIRECTORY "${CMAKE_SOURCE_DIR}"
            COMMENT "Writing the closed loop as SSP" VERBATIM)
        add_custom_target(check_fmus ALL DEPENDS "${stamp}" "${ssp}")
    endif()
endif()
