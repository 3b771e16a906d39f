# rths_view_bench: real-time overruns and wake-up to command with and without the live view (and a
# headless Chromium on its page), the view's CPU and RSS. Prints figures; never run as a test.
add_executable(rths_view_bench ${CMAKE_CURRENT_LIST_DIR}/view_bench.cpp)
target_link_libraries(rths_view_bench PRIVATE rths_bench_support rths_view CLI11::CLI11
                      PkgConfig::HTTPLIB)
add_dependencies(rths_view_bench rths-substructure-node rths-actuator-emulator)
rths_warnings(rths_view_bench)
