# plots_bench: what the plots cost against the run (issue 39's target: with plots, at most 2x the
# --no-plots time) for the RTHS benchmark's case 1 and the paper frame, timing `rths run` itself.
add_executable(plots_bench ${CMAKE_CURRENT_SOURCE_DIR}/plots_bench.cpp)
add_dependencies(plots_bench rths)
target_compile_definitions(plots_bench PRIVATE RTHS_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
                                               RTHS_CLI="$<TARGET_FILE:rths>")
rths_warnings(plots_bench)
