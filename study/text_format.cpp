#include "study/text_format.h"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rths::study {
namespace {

// Keeps the first error: later ones are usually consequences of it.
class FirstError final : public google::protobuf::io::ErrorCollector {
 public:
  explicit FirstError(std::string source) : source_(std::move(source)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    if (first_.empty()) {
      first_ = source_ + ":" + std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " +
               message;
    }
  }
  void AddWarning(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
  const std::string& first() const { return first_; }

 private:
  std::string source_, first_;
};

}  // namespace

void parse_text_format(const std::string& text, const std::string& source_name,
                       google::protobuf::Message& message) {
  FirstError errors(source_name);
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &message)) {
    throw std::invalid_argument(errors.first().empty()
                                    ? source_name + ": cannot parse " + message.GetTypeName()
                                    : errors.first());
  }
}

std::string read_text_file(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open " + what + " " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text_format(const google::protobuf::Message& message, const std::filesystem::path& path,
                       const std::vector<std::string>& comment) {
  std::string body;
  if (!google::protobuf::TextFormat::PrintToString(message, &body)) {
    throw std::runtime_error(path.string() + ": cannot print " + message.GetTypeName());
  }
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  for (const auto& line : comment) out << "# " << line << "\n";
  out << body;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": cannot write " + message.GetTypeName());
}

}  // namespace rths::study
