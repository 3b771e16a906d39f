# rths_controller_rt_bench: the controller link in real time across two network namespaces (a
# 1024 Hz coordinator and its CONTROLLER node, the controller emulator's plant paced at 4096 Hz):
# the record's round trip against the injected lag, and the HOLD when the emulator is killed or
# silenced. Prints figures; needs root; never run as a test (tests/controller_node runs a few).
add_executable(rths_controller_rt_bench ${CMAKE_CURRENT_LIST_DIR}/controller_rt.cpp)
target_link_libraries(rths_controller_rt_bench PRIVATE rths_controller_trial CLI11::CLI11)
target_compile_definitions(rths_controller_rt_bench PRIVATE
  RTHS_BINARY_DIR="${PROJECT_BINARY_DIR}"
  RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
add_dependencies(rths_controller_rt_bench rths-coordinator rths-substructure-node
                 rths-actuator-emulator rths-controller-node rths-controller-emulator)
rths_warnings(rths_controller_rt_bench)
