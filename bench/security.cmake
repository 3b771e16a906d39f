# rths_security_bench: lockstep throughput of the three rths processes with DDS Security on, as a
# ratio to the same run with it off. Prints figures; never run as a test.
add_executable(rths_security_bench ${CMAKE_CURRENT_LIST_DIR}/security_bench.cpp)
target_link_libraries(rths_security_bench PRIVATE rths_runtime CLI11::CLI11)
target_compile_definitions(rths_security_bench PRIVATE
  RTHS_BINARY_DIR="${PROJECT_BINARY_DIR}"
  RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
add_dependencies(rths_security_bench rths-coordinator rths-substructure-node rths-actuator-emulator)
rths_warnings(rths_security_bench)
