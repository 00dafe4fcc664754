# libFuzzer targets (the fuzz preset: clang with ASan and UBSan on every object):
# fuzz_deserialize (state blobs, forged ones included) and fuzz_calls (FMI call
# sequences) for each model, linked with the FMI 2 API file and the same objects.
foreach(id IN LISTS STO_MODELS)
    foreach(target fuzz_deserialize fuzz_calls)
        add_executable(${target}-${id} "${CMAKE_SOURCE_DIR}/tools/abuse/${target}.c"
                       "${SRC}/fmi2/fmi2_functions.c" "${SRC}/${STO_${id}_MODEL}")
        target_include_directories(${target}-${id} SYSTEM PRIVATE "${STO_FMI_INCLUDE_DIR}")
        target_link_libraries(${target}-${id} PRIVATE sto_instance sto_core)
        target_link_options(${target}-${id} PRIVATE -fsanitize=fuzzer)
        if(NOT STO_FUZZ_FORGED)
            target_compile_definitions(${target}-${id} PRIVATE FUZZ_NO_FORGED)
        endif()
    endforeach()
endforeach()
