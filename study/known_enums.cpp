#include "study/known_enums.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include <stdexcept>
#include <vector>

namespace rths::study {

namespace {

using google::protobuf::EnumDescriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Message;
using google::protobuf::Reflection;

void refuse(const std::string& source, const std::string& path, int value,
            const EnumDescriptor& type) {
  std::string known;
  for (int i = 0; i < type.value_count(); ++i) {
    if (i > 0) known += ", ";
    known += type.value(i)->name();
  }
  std::string text = source;
  text += ": ";
  text += path;
  text += ": ";
  text += std::to_string(value);
  text += " is not a known value (";
  text += known;
  text += ")";
  throw std::invalid_argument(text);
}

void check(const Message& message, const std::string& prefix, const std::string& source);

void check_field(const Message& message, const FieldDescriptor& field, const std::string& path,
                 const std::string& source) {
  const Reflection& r = *message.GetReflection();
  if (field.cpp_type() == FieldDescriptor::CPPTYPE_ENUM) {
    const EnumDescriptor& type = *field.enum_type();
    if (!field.is_repeated()) {
      const int value = r.GetEnumValue(message, &field);
      if (!type.FindValueByNumber(value)) refuse(source, path, value, type);
      return;
    }
    for (int i = 0; i < r.FieldSize(message, &field); ++i) {
      const int value = r.GetRepeatedEnumValue(message, &field, i);
      if (!type.FindValueByNumber(value))
        refuse(source, path + "[" + std::to_string(i) + "]", value, type);
    }
    return;
  }
  if (field.cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) return;
  if (!field.is_repeated()) {
    check(r.GetMessage(message, &field), path + ".", source);
    return;
  }
  for (int i = 0; i < r.FieldSize(message, &field); ++i)
    check(r.GetRepeatedMessage(message, &field, i), path + "[" + std::to_string(i) + "].", source);
}

void check(const Message& message, const std::string& prefix, const std::string& source) {
  std::vector<const FieldDescriptor*> fields;
  message.GetReflection()->ListFields(message, &fields);
  for (const FieldDescriptor* field : fields)
    check_field(message, *field, prefix + field->name(), source);
}

}  // namespace

void require_known_enums(const Message& message, const std::string& source) {
  check(message, "", source);
}

}  // namespace rths::study
