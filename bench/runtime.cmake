# rths_runtime_bench: lockstep steps/s and step latency over Cyclone DDS on loopback beside a
# ping-pong of the same payload, and real-time pacing at 1024 / 4096 Hz beside a bare
# clock_nanosleep loop. Prints figures; never run as a test.
add_executable(rths_runtime_bench ${CMAKE_CURRENT_LIST_DIR}/runtime_bench.cpp)
target_link_libraries(rths_runtime_bench PRIVATE rths_bench_support CLI11::CLI11)
target_compile_definitions(rths_runtime_bench PRIVATE
  RTHS_BINARY_DIR="${PROJECT_BINARY_DIR}"
  RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
add_dependencies(rths_runtime_bench rths-substructure-node rths-actuator-emulator)
rths_warnings(rths_runtime_bench)
