# plots_bench: what the plots cost against the run (issue 39's target: with plots, at most 2x the
# --no-plots time) for the RTHS benchmark's case 1 and the paper frame.
add_executable(plots_bench ${CMAKE_CURRENT_SOURCE_DIR}/plots_bench.cpp)
target_link_libraries(plots_bench PRIVATE rths_analysis rths_results)
target_compile_definitions(plots_bench PRIVATE RTHS_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
rths_warnings(plots_bench)
