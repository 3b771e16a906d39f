# sparse_bench: cost per step and before the first step of large sparse models (Matrix Market
# shear buildings of 10 to 10,000 DOFs) and of a 300-DOF condensed (dense) one (prints figures;
# not a test). It needs only rths's own libraries, so it is built with or without the tests (the
# top CMakeLists.txt includes this file when RTHS_BUILD_TESTS is off): docs/performance.md quotes it.
add_executable(sparse_bench ${CMAKE_CURRENT_LIST_DIR}/sparse_bench.cpp)
target_link_libraries(sparse_bench PRIVATE rths_study)
target_include_directories(sparse_bench PRIVATE ${PROJECT_SOURCE_DIR})
target_compile_definitions(sparse_bench PRIVATE RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
# build/bench/sparse_bench whichever CMakeLists.txt includes this file.
set_target_properties(sparse_bench PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/bench)
rths_warnings(sparse_bench)
