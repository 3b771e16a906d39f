# compensation_bench: the compensated studies (paper frame with the identified MTS actuator, the
# RTHS benchmark plant) with NRMSE, peak error and J1-J9 per case, against the issue's targets.
add_executable(compensation_bench ${CMAKE_CURRENT_SOURCE_DIR}/compensation_bench.cpp)
target_link_libraries(compensation_bench PRIVATE rths_study_run)
target_compile_definitions(compensation_bench PRIVATE RTHS_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
rths_warnings(compensation_bench)
