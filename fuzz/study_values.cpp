// The study_values fuzz entry (targets.h): a study config either refused with an error that names
// where, or accepted holding only values that are what they say. Not a crash hunt (study_config
// is): its findings are configs the loader took while quietly running something else.
#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "fuzz/targets.h"
#include "study/study.h"

namespace rths::fuzz {
namespace {

namespace pb = google::protobuf;

// Fields that, when given (proto3 optional: present), must be > 0: the loader's default stands
// only for an omitted value, never for a given 0 or a negative one.
const std::set<std::string>& positive_when_given() {
  static const std::set<std::string> fields{"rths.config.Sdof.mass",
                                            "rths.config.DelayStage.BenchmarkPlant.mass",
                                            "rths.config.DelayStage.BenchmarkPlant.stiffness"};
  return fields;
}

void add_names(const pb::Descriptor* d, std::set<std::string>& names,
               std::set<const pb::Descriptor*>& seen) {
  if (!seen.insert(d).second) return;
  for (int i = 0; i < d->field_count(); ++i) {
    names.insert(d->field(i)->name());
    if (d->field(i)->message_type()) add_names(d->field(i)->message_type(), names, seen);
  }
}

// Every field name a study can hold, at any depth.
const std::set<std::string>& study_field_names() {
  static const std::set<std::string> names = [] {
    std::set<std::string> out;
    std::set<const pb::Descriptor*> seen;
    add_names(config::Study::descriptor(), out, seen);
    return out;
  }();
  return names;
}

// A refusal names where: a field of the study (e.g. "structure.sdof.mass") or a line:column.
void check_refusal(const std::string& what) {
  for (std::size_t at = what.find_first_of("0123456789"); at != std::string::npos;
       at = what.find_first_of("0123456789", at + 1))
    if (at > 0 && what[at - 1] == ':') return;  // "fuzz:3:7: ..." or "line 3:7"
  std::string word;
  for (const char c : what + " ") {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') {
      word += c;
      continue;
    }
    if (study_field_names().count(word)) return;
    word.clear();
  }
  throw std::logic_error("study refused without naming a field or a place: " + what);
}

void check_value(const pb::FieldDescriptor* f, double value, const std::string& path) {
  if (!std::isfinite(value))
    throw std::logic_error("study accepted with " + path + " = " + std::to_string(value));
  if (f->has_presence() && positive_when_given().count(f->full_name()) && !(value > 0))
    throw std::logic_error("study accepted with " + path + " = " + std::to_string(value) +
                           " (given: must be > 0; its default stands only for an omitted value)");
}

// Walks an accepted study: no value that is not finite, no given value its default would replace.
void check_accepted(const pb::Message& m, const std::string& path) {
  const pb::Reflection* r = m.GetReflection();
  std::vector<const pb::FieldDescriptor*> set;
  r->ListFields(m, &set);
  for (const pb::FieldDescriptor* f : set) {
    const std::string here = path.empty() ? f->name() : path + "." + f->name();
    const bool floating = f->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE ||
                          f->cpp_type() == pb::FieldDescriptor::CPPTYPE_FLOAT;
    const bool message = f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE;
    const int n = f->is_repeated() ? r->FieldSize(m, f) : 1;
    for (int i = 0; i < n; ++i) {
      const std::string at = f->is_repeated() ? here + "[" + std::to_string(i) + "]" : here;
      if (message)
        check_accepted(f->is_repeated() ? r->GetRepeatedMessage(m, f, i) : r->GetMessage(m, f), at);
      if (!floating) continue;
      const bool dbl = f->cpp_type() == pb::FieldDescriptor::CPPTYPE_DOUBLE;
      const double v = f->is_repeated()
                           ? (dbl ? r->GetRepeatedDouble(m, f, i)
                                  : static_cast<double>(r->GetRepeatedFloat(m, f, i)))
                           : (dbl ? r->GetDouble(m, f) : static_cast<double>(r->GetFloat(m, f)));
      check_value(f, v, at);
    }
  }
}

}  // namespace

int study_values(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  config::Study study;
  try {
    study = study::parse_study(text, "fuzz");
  } catch (const std::invalid_argument& e) {
    check_refusal(e.what());
    return 0;
  } catch (const std::runtime_error& e) {
    check_refusal(e.what());
    return 0;
  }
  check_accepted(study, "");
  return 0;
}

}  // namespace rths::fuzz
