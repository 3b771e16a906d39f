#pragma once
// What a figure test reads back of a PNG: its width and height (px), from its IHDR chunk.

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <utility>

namespace rths::test {

// {width, height} in px; {0, 0} when the file cannot be read.
inline std::pair<std::uint32_t, std::uint32_t> png_size(const std::filesystem::path& png) {
  std::ifstream in(png, std::ios::binary);
  std::array<unsigned char, 24> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  const auto be32 = [&](std::size_t at) {
    return std::uint32_t{head[at]} << 24 | std::uint32_t{head[at + 1]} << 16 |
           std::uint32_t{head[at + 2]} << 8 | std::uint32_t{head[at + 3]};
  };
  return {be32(16), be32(20)};
}

}  // namespace rths::test
