#pragma once
// SHA-256 of a file, as 64 lower-case hex digits (what `sha256sum` prints), through OpenSSL's
// libcrypto. Used to name the data a study read and to refuse a file that is not the one a config
// or data/SHA256SUMS expects.
//
//   file_sha256(path)  reads the file in 1 MiB blocks; throws std::invalid_argument naming the
//                      file when it cannot be opened or read
//   bytes_sha256(data, size)  of `size` bytes in memory

#include <cstddef>
#include <filesystem>
#include <string>

namespace rths::util {

std::string file_sha256(const std::filesystem::path& path);
std::string bytes_sha256(const void* data, std::size_t size);

}  // namespace rths::util
