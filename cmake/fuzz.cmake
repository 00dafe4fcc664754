# libFuzzer targets (the fuzz preset: clang with ASan and UBSan on every object):
# fuzz_deserialize (state blobs, forged ones included) and fuzz_calls (FMI 2 call
# sequences) linked with the FMI 2 API file, fuzz_fmi3_calls (FMI 3 call sequences,
# states included) with the FMI 3 one, for each model, over the same objects.
foreach(id IN LISTS STO_MODELS)
    foreach(target fuzz_deserialize fuzz_calls fuzz_fmi3_calls)
        set(api fmi2)
        if(target STREQUAL fuzz_fmi3_calls)
            set(api fmi3)
        endif()
        add_executable(${target}-${id} "${CMAKE_SOURCE_DIR}/tools/abuse/${target}.c"
                       "${SRC}/${api}/${api}_functions.c" "${SRC}/${STO_${id}_MODEL}")
        target_include_directories(${target}-${id} SYSTEM PRIVATE "${STO_FMI_INCLUDE_DIR}")
        target_link_libraries(${target}-${id} PRIVATE sto_instance sto_core)
        target_link_options(${target}-${id} PRIVATE -fsanitize=fuzzer)
        # a model that reads its resources (ModelObserver) finds the committed ones
        set(resources "${CMAKE_SOURCE_DIR}/fmu/src/models/ModelObserver/resources")
        target_compile_definitions(${target}-${id} PRIVATE
            "FUZZ_RESOURCE_URI=\"file://${resources}\"" "FUZZ_RESOURCE_PATH=\"${resources}/\"")
        if(NOT STO_FUZZ_FORGED)
            target_compile_definitions(${target}-${id} PRIVATE FUZZ_NO_FORGED)
        endif()
    endforeach()
endforeach()
# fuzz_model_resource: ModelObserver's resource file (the term program) and the states of
# an instance that read it, through the FMI 2 API file.
if("ModelObserver" IN_LIST STO_MODELS)
    add_executable(fuzz_model_resource-ModelObserver
                   "${CMAKE_SOURCE_DIR}/tools/abuse/fuzz_model_resource.c"
                   "${SRC}/fmi2/fmi2_functions.c" "${SRC}/${STO_ModelObserver_MODEL}")
    target_include_directories(fuzz_model_resource-ModelObserver SYSTEM PRIVATE
                               "${STO_FMI_INCLUDE_DIR}")
    target_link_libraries(fuzz_model_resource-ModelObserver PRIVATE sto_instance sto_core)
    target_link_options(fuzz_model_resource-ModelObserver PRIVATE -fsanitize=fuzzer)
    if(NOT STO_FUZZ_FORGED)
        target_compile_definitions(fuzz_model_resource-ModelObserver PRIVATE FUZZ_NO_FORGED)
    endif()
endif()
