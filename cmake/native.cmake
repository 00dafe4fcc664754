# The Python package's native library (harness.native_library loads it by ctypes):
# the master loop and the robot batch entry points over the same core objects.
# Its core is compiled for longer chains than the FMUs' 7 joints (the offline robot
# path: identify, validate --robot), over the same sources.
set(STO_NATIVE_MAX_JOINTS 12 CACHE STRING "Joints of a serial robot at most, offline")
add_library(sto_core_offline STATIC ${core_paths})
target_include_directories(sto_core_offline PUBLIC "${SRC}/core")
math(EXPR STO_NATIVE_MAX_SIGNALS "2 * ${STO_NATIVE_MAX_JOINTS}")
target_compile_definitions(sto_core_offline PUBLIC RB_MAX_JOINTS=${STO_NATIVE_MAX_JOINTS}
                           FL_MAX_SIGNALS=${STO_NATIVE_MAX_SIGNALS})
target_link_libraries(sto_core_offline PUBLIC ${STO_LIBM})
add_library(sto_native SHARED ${STO_NATIVE_SOURCES})
target_link_libraries(sto_native PRIVATE sto_core_offline)
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
