# sparse_bench: cost per step and before the first step of large sparse models (Matrix Market
# shear buildings of 10 to 10,000 DOFs) and of a 300-DOF condensed (dense) one (prints figures;
# not a test).
add_executable(sparse_bench ${CMAKE_CURRENT_SOURCE_DIR}/sparse_bench.cpp)
target_link_libraries(sparse_bench PRIVATE rths_study)
target_include_directories(sparse_bench PRIVATE ${PROJECT_SOURCE_DIR})
target_compile_definitions(sparse_bench PRIVATE RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
rths_warnings(sparse_bench)
