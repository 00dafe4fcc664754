# The Python package's native library (harness.native_library loads it by ctypes):
# the master loop and the robot batch entry points over the same core objects.
add_library(sto_native SHARED ${STO_NATIVE_SOURCES})
target_link_libraries(sto_native PRIVATE sto_core)
# The ctypes entry points are its interface; the core stays hidden.
set_target_properties(sto_native PROPERTIES C_VISIBILITY_PRESET default)
if(SKBUILD)
    # A wheel: the library and the FMUs the build made beside it (./build.sh fmus).
    install(TARGETS sto_native LIBRARY DESTINATION harness/lib RUNTIME DESTINATION harness/lib)
    set(STO_WHEEL_FMU_DIR "${CMAKE_SOURCE_DIR}/build/fmus" CACHE PATH "FMUs the wheel ships")
    file(GLOB wheel_fmus "${STO_WHEEL_FMU_DIR}/*.fmu")
    if(wheel_fmus)
        install(FILES ${wheel_fmus} DESTINATION harness/data)
        # the FMI 3 binary `sto-harness fmu --model --fmi-version 3` writes model FMUs from
        set(fmi3_template "${STO_WHEEL_FMU_DIR}/../fmi3/ModelObserver.fmu")
        if(EXISTS "${fmi3_template}")
            install(FILES "${fmi3_template}" DESTINATION harness/data/fmi3)
        endif()
    else()
        message(WARNING "No FMUs in ${STO_WHEEL_FMU_DIR}: the wheel ships none "
                        "(build them first: ./build.sh fmus)")
    endif()
else()
    set_target_properties(sto_native PROPERTIES
        LIBRARY_OUTPUT_DIRECTORY "${STO_NATIVE_OUTPUT_DIR}"
        RUNTIME_OUTPUT_DIRECTORY "${STO_NATIVE_OUTPUT_DIR}")
endif()
