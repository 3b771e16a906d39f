# rths_mac_bench: the run secret's per-message MAC alone (sign and verify, ns per message) beside
# OpenSSL's EVP_MAC HMAC re-initialised per message. Prints figures; never run as a test.
find_package(OpenSSL 3 REQUIRED)
add_executable(rths_mac_bench ${CMAKE_CURRENT_LIST_DIR}/mac_bench.cpp)
target_link_libraries(rths_mac_bench PRIVATE rths_transport OpenSSL::Crypto)
rths_warnings(rths_mac_bench)
