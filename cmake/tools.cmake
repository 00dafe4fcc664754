# Drivers over the same objects: instruction counts and step costs (bench/perf/), the
# closed loop under valgrind (tools/abuse/) and the platform importer (tools/dist/).
function(sto_add_fmi2_driver name source id)
    add_executable(${name} "${CMAKE_SOURCE_DIR}/${source}" "${SRC}/fmi2/fmi2_functions.c"
                   "${SRC}/${STO_${id}_MODEL}")
    target_include_directories(${name} SYSTEM PRIVATE "${STO_FMI_INCLUDE_DIR}")
    target_link_libraries(${name} PRIVATE sto_instance sto_core)
    target_compile_options(${name} PRIVATE -g)
    target_compile_definitions(${name} PRIVATE _POSIX_C_SOURCE=200809L)  # clock_gettime
endfunction()
sto_add_fmi2_driver(step_driver bench/perf/step_driver.c SuperTwistingObserver)
sto_add_fmi2_driver(robot_fmu_step bench/perf/robot_fmu_step.c RobotObserver)

add_executable(robot_step "${CMAKE_SOURCE_DIR}/bench/perf/robot_step.c")
target_link_libraries(robot_step PRIVATE sto_core)
target_compile_definitions(robot_step PRIVATE _POSIX_C_SOURCE=200809L)

# An importer that loads an FMU's binary at run time (valgrind's closed loop).
add_executable(closed_loop "${CMAKE_SOURCE_DIR}/tools/abuse/closed_loop.c")
target_include_directories(closed_loop SYSTEM PRIVATE "${STO_FMI_INCLUDE_DIR}")
target_compile_options(closed_loop PRIVATE -g)
target_link_libraries(closed_loop PRIVATE ${CMAKE_DL_LIBS} ${STO_LIBM})
