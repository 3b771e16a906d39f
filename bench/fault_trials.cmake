# fault_trials: N real-time runs, each with one process killed (SIGKILL) or stalled (SIGSTOP) at a
# random step; prints per trial and in total how fast and how completely the fail-safe acted.
# Never run as a test (tests/runtime/fault_trials_test.cpp runs a few fixed trials).
add_executable(fault_trials ${CMAKE_CURRENT_LIST_DIR}/fault_trials.cpp)
target_link_libraries(fault_trials PRIVATE rths_test_support rths_rt_check CLI11::CLI11)
target_compile_definitions(fault_trials PRIVATE
  RTHS_BINARY_DIR="${PROJECT_BINARY_DIR}"
  RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
add_dependencies(fault_trials rths-coordinator rths-substructure-node rths-actuator-emulator)
rths_warnings(fault_trials)
