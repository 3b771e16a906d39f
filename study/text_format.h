#pragma once
// Protobuf text-format configs: parsing with an error that names source, line, column and field,
// and reading a config file. Every config of the project (studies, sites, joint-lag studies)
// goes through here, so every config error reads the same way.

#include <google/protobuf/message.h>

#include <filesystem>
#include <string>
#include <vector>

namespace rths::study {

// Parses `text` into `message`. Throws std::invalid_argument "SOURCE:LINE:COL: message" on syntax
// errors, unknown fields and wrong types.
void parse_text_format(const std::string& text, const std::string& source_name,
                       google::protobuf::Message& message);

// The whole file as text. Throws std::invalid_argument naming the file when it cannot be read.
std::string read_text_file(const std::filesystem::path& path, const std::string& what);

// Writes `message` in text format to `path` (parent folders created), after `comment` lines each
// prefixed "# ". Doubles are printed so that they read back to the same value. Throws
// std::runtime_error naming the file when it cannot be written.
void write_text_format(const google::protobuf::Message& message, const std::filesystem::path& path,
                       const std::vector<std::string>& comment = {});

}  // namespace rths::study
