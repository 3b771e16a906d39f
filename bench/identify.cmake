# identify_bench: wall time of `rths identify` per record (the shared MTS chirp export and a
# one-minute 1 kHz record of the same rig made by the project's generator), with the held-out
# errors it reaches (prints figures; not a test).
add_executable(identify_bench ${CMAKE_CURRENT_SOURCE_DIR}/identify_bench.cpp)
target_link_libraries(identify_bench PRIVATE rths_identify)
target_include_directories(identify_bench PRIVATE ${PROJECT_SOURCE_DIR})
add_dependencies(identify_bench rths)
target_compile_definitions(identify_bench PRIVATE RTHS_EXECUTABLE="$<TARGET_FILE:rths>"
                           RTHS_DATA_DIR="${PROJECT_SOURCE_DIR}/data")
rths_warnings(identify_bench)
