# rths_bench_support: the set-up the distributed benchmarks share (the SDOF study text, a run's
# directory, node processes and coordinator). Linked by the benchmarks only.
add_library(rths_bench_support STATIC ${CMAKE_CURRENT_LIST_DIR}/bench_support.cpp)
target_link_libraries(rths_bench_support PUBLIC rths_coordinator)
target_compile_definitions(rths_bench_support PRIVATE
  RTHS_BINARY_DIR="${PROJECT_BINARY_DIR}"
  RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
rths_warnings(rths_bench_support)
