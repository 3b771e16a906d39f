# rths_secret_bench: what the run secret's MACs cost lockstep and real-time runs (pairs without and
# with it), and what a flood of forged messages costs a real-time run. Prints figures; never a test.
add_executable(rths_secret_bench ${CMAKE_CURRENT_LIST_DIR}/secret_bench.cpp)
target_link_libraries(rths_secret_bench PRIVATE rths_bench_support CLI11::CLI11)
add_dependencies(rths_secret_bench rths-substructure-node rths-actuator-emulator)
rths_warnings(rths_secret_bench)
