// Strict reading of typed JSON: every field of an object must be present and known, every
// value of the expected type; errors name the JSON path ("$.runs[2].counters[0].source").
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "contactlab/kernels/error.hpp"

namespace contactlab {

// A result or config file that does not follow its schema.
class SchemaError : public InputError {
 public:
  using InputError::InputError;
};

// One JSON value and where it is.
class JsonIn {
 public:
  JsonIn(const nlohmann::json& value, std::string path) : value_(&value), path_(std::move(path)) {}
  const nlohmann::json& value() const { return *value_; }
  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& what) const { throw SchemaError(path_ + ": " + what); }
  [[noreturn]] void wrong_type(const char* expected) const {
    fail(std::string("expected ") + expected + ", got " + value_->type_name());
  }

 private:
  const nlohmann::json* value_;
  std::string path_;
};

// The fields of one object: read each with field(); finish() rejects keys never read.
class ObjectIn {
 public:
  explicit ObjectIn(const JsonIn& in) : in_(in) {
    if (!in.value().is_object()) in.wrong_type("object");
  }
  JsonIn field(const std::string& key) {
    const auto it = in_.value().find(key);
    if (it == in_.value().end()) in_.fail("missing field '" + key + "'");
    seen_.insert(key);
    return JsonIn(*it, in_.path() + "." + key);
  }
  // For configs, whose fields may be left out: the field, or nothing when it is absent.
  std::optional<JsonIn> optional_field(const std::string& key) {
    if (!in_.value().contains(key)) return std::nullopt;
    return field(key);
  }
  template <class T>
  void operator()(const std::string& key, T& out) {
    read(field(key), out);
  }
  void finish() const {
    for (const auto& item : in_.value().items()) {
      if (!seen_.count(item.key())) in_.fail("unknown field '" + item.key() + "'");
    }
  }
  const JsonIn& in() const { return in_; }

 private:
  JsonIn in_;
  std::set<std::string> seen_;
};

inline void read(const JsonIn& in, bool& out) {
  if (!in.value().is_boolean()) in.wrong_type("boolean");
  out = in.value().get<bool>();
}
inline void read(const JsonIn& in, double& out) {
  if (!in.value().is_number()) in.wrong_type("number");
  out = in.value().get<double>();
}
inline void read(const JsonIn& in, std::string& out) {
  if (!in.value().is_string()) in.wrong_type("string");
  out = in.value().get<std::string>();
}
inline void read(const JsonIn& in, std::uint64_t& out) {
  // JSON built in code holds small integers as signed: accept those that are >= 0.
  const bool non_negative = in.value().is_number_unsigned() ||
                            (in.value().is_number_integer() && in.value().get<std::int64_t>() >= 0);
  if (!non_negative) in.fail("expected non-negative integer, got " + in.value().dump());
  out = in.value().get<std::uint64_t>();
}
inline void read(const JsonIn& in, std::uint32_t& out) {
  std::uint64_t v = 0;
  read(in, v);
  if (v > std::numeric_limits<std::uint32_t>::max())
    in.fail("value " + std::to_string(v) + " too large");
  out = static_cast<std::uint32_t>(v);
}
inline void read(const JsonIn& in, int& out) {
  if (!in.value().is_number_integer()) in.wrong_type("integer");
  const auto v = in.value().get<std::int64_t>();
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    in.fail("integer " + std::to_string(v) + " out of range");
  }
  out = static_cast<int>(v);
}
template <class T>
void read(const JsonIn& in, std::optional<T>& out) {
  if (in.value().is_null()) {
    out.reset();
    return;
  }
  T value{};
  read(in, value);
  out = std::move(value);
}
template <class T>
void read(const JsonIn& in, std::vector<T>& out) {
  if (!in.value().is_array()) in.wrong_type("array");
  out.clear();
  out.resize(in.value().size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    read(JsonIn(in.value()[i], in.path() + "[" + std::to_string(i) + "]"), out[i]);
  }
}
template <class T, std::size_t N>
void read(const JsonIn& in, std::array<T, N>& out) {
  if (!in.value().is_array()) in.wrong_type("array");
  if (in.value().size() != N) {
    in.fail("expected " + std::to_string(N) + " elements, got " +
            std::to_string(in.value().size()));
  }
  for (std::size_t i = 0; i < N; ++i) {
    read(JsonIn(in.value()[i], in.path() + "[" + std::to_string(i) + "]"), out[i]);
  }
}

// Any value, kept as it is (a part read later, or by another reader).
inline void read(const JsonIn& in, nlohmann::json& out) { out = in.value(); }

// An object used as a map: any keys, each value of type T.
template <class T>
void read(const JsonIn& in, std::map<std::string, T>& out) {
  if (!in.value().is_object()) in.wrong_type("object");
  out.clear();
  for (const auto& item : in.value().items()) {
    read(JsonIn(item.value(), in.path() + "." + item.key()), out[item.key()]);
  }
}

// null for an empty optional; finite doubles only (JSON has no NaN or infinity).
template <class T>
nlohmann::json optional_json(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

}  // namespace contactlab
