# The platform importer (tools/dist/run_reference.c): built for each platform that
# can run here (natively, under qemu-user or wine) to replay the FMUs' reference results.
add_executable(run_reference "${CMAKE_SOURCE_DIR}/tools/dist/run_reference.c")
target_include_directories(run_reference SYSTEM PRIVATE "${STO_FMI_INCLUDE_DIR}")
target_link_libraries(run_reference PRIVATE ${CMAKE_DL_LIBS} ${STO_LIBM})
