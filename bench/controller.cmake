# rths_controller_bench: the time a controller node's step adds over an actuator emulator's (the
# UDP round trip to the controller emulator, another process, and the frames). Prints figures;
# never run as a test.
add_executable(rths_controller_bench ${CMAKE_CURRENT_LIST_DIR}/controller_bench.cpp)
target_link_libraries(rths_controller_bench PRIVATE rths_bench_support rths_controller_node
                      rths_actuator_emulator CLI11::CLI11)
target_compile_definitions(rths_controller_bench PRIVATE RTHS_BINARY_DIR="${PROJECT_BINARY_DIR}")
add_dependencies(rths_controller_bench rths-controller-emulator)
rths_warnings(rths_controller_bench)
