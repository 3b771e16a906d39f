# sweep_bench: throughput of the sweep's SIMD batch kernel (prints figures; not a test).
add_executable(sweep_bench ${CMAKE_CURRENT_SOURCE_DIR}/sweep_bench.cpp)
target_link_libraries(sweep_bench PRIVATE rths_sweep)
target_compile_definitions(sweep_bench PRIVATE RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
rths_warnings(sweep_bench)
