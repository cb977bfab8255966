// Field tables: one list of a record's JSON fields drives both writing and strict reading.
// A field name is thus never written one way and read another.
//
//   template <> struct FieldTable<Work> {
//     static constexpr auto kFields = std::tuple{
//         field("tests", &Work::tests_),                        // required
//         field("kind", &Work::kind_).via(EnumCodec<&parse_kind>{}),  // enum by its string form
//         field("notes", &Work::notes_).may_be_absent(),        // older files lack it
//         field("version", &Work::version_).checked(check_version),   // checked as it is read
//         computed("sets", &Work::sets, "size / ways"),         // written from, checked against
//         group("env", field("A", &Work::a_), field("B", &Work::b_)),  // a nested object
//         field_list(kWorkCosts)};  // (name, member) pairs kept elsewhere, e.g. kMachineCostFields
//     static void validate(const JsonIn& in, const Work& w);  // optional: cross-field checks
//   };
//
// to_json_value(record) writes it; read(JsonIn, record) reads it with json_reader.hpp's rules
// (unknown keys rejected, missing ones named, every error with the JSON path). A parse function's
// InputError is reported at the enclosing object, prefixed with the field name.
//
// A table is declared before any use in the one source file that writes and reads its record,
// or, where another file's tables hold the record too, in a private header both include
// (tuner/src/context_tables.hpp); other files go through the to_json / read functions declared
// in a public header. The generic functions below must never see a record with a table in one
// file and without one in another: to_json_value<T> would then be two functions under one name,
// and the linker keeps either.
#pragma once

#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "contactlab/support/json_reader.hpp"

namespace contactlab::tuner {

// Specialise with `static constexpr auto kFields = std::tuple{...}` (and, when fields depend on
// each other, `static void validate(const JsonIn&, const T&)`, run after every field is read).
template <class T>
struct FieldTable;

template <class T>
concept Described = requires {
  FieldTable<T>::kFields;
};

template <class T>
nlohmann::json to_json_value(const T& value);
template <Described T>
void read_record(const JsonIn& in, T& out);

}  // namespace contactlab::tuner

namespace contactlab {

// A record with a table is read by it. Declared beside JsonIn (contactlab::support), where
// argument-dependent lookup finds it for a record of any namespace, an unnamed one included:
// json_reader.hpp's templates read the vectors, maps and optionals of records that way.
template <tuner::Described T>
void read(const JsonIn& in, T& out);

}  // namespace contactlab

namespace contactlab::tuner {

// Values go through to_json_value and read.
struct PlainCodec {
  template <class M>
  nlohmann::json encode(const M& value) const {
    return to_json_value(value);
  }
  template <class M>
  void decode(const JsonIn& in, M& out) const {
    read(in, out);
  }
};

// An enum by its string form: to_string(e) and Parse(text), which throws InputError.
template <auto Parse>
struct EnumCodec {
  template <class E>
  nlohmann::json encode(const E& value) const {
    return std::string(to_string(value));
  }
  template <class E>
  void decode(const JsonIn& in, E& out) const {
    std::string text;
    contactlab::read(in, text);
    out = Parse(text);
  }
};

struct NoCheck {
  template <class M>
  constexpr void operator()(const JsonIn&, const M&) const {}
};

// Absent fields are errors unless the field is new and files written before it must still read,
// or the field is a std::optional that only some records have (written only when it has a
// value: e.g. a tuning method's own fields in the tune report).
enum class Presence { kRequired, kMayBeAbsent, kOnlyWhenSet };

namespace detail {
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
}  // namespace detail

template <class T, class M, class Codec = PlainCodec, class Check = NoCheck>
struct Field {
  using Record = T;
  const char* name_;
  M T::*member_;
  Presence presence_ = Presence::kRequired;
  Codec codec_{};
  Check check_{};

  constexpr auto may_be_absent() const {
    return Field{name_, member_, Presence::kMayBeAbsent, codec_, check_};
  }
  constexpr auto only_when_set() const {
    static_assert(detail::IsOptional<M>::value, "only_when_set() is for std::optional members");
    return Field{name_, member_, Presence::kOnlyWhenSet, codec_, check_};
  }
  template <class C>
  constexpr auto via(C other) const {
    return Field<T, M, C, Check>{name_, member_, presence_, other, check_};
  }
  // `hook(const JsonIn& at, const M& value)` runs as soon as the value is read (before the
  // fields after it, e.g. a version that decides how the rest reads).
  template <class K>
  constexpr auto checked(K hook) const {
    return Field<T, M, Codec, K>{name_, member_, presence_, codec_, hook};
  }

  void write_into(nlohmann::json& j, const T& record) const {
    if constexpr (detail::IsOptional<M>::value) {
      if (presence_ == Presence::kOnlyWhenSet && !(record.*member_)) return;
    }
    j[name_] = codec_.encode(record.*member_);
  }
  void read_from(ObjectIn& o, T& record) const {
    std::optional<JsonIn> at;
    if (presence_ != Presence::kRequired) {
      at = o.optional_field(name_);
      if (!at) return;
    } else {
      at = o.field(name_);
    }
    try {
      codec_.decode(*at, record.*member_);
    } catch (const SchemaError&) {
      throw;
    } catch (const InputError& e) {
      o.in().fail(std::string(name_) + ": " + e.what());
    }
    check_(*at, record.*member_);
  }
};

template <class T, class M>
constexpr Field<T, M> field(const char* name, M T::*member) {
  return {name, member};
}

// A value derived from other fields (a const member function): written from it, and on reading
// checked against it. List it after the fields it derives from.
template <class T, class R>
struct Computed {
  const char* name_;
  R (T::*get_)() const;
  const char* formula_;  // for the message: "sets = 3 does not match <formula> = 4"

  void write_into(nlohmann::json& j, const T& record) const {
    j[name_] = to_json_value((record.*get_)());
  }
  void read_from(ObjectIn& o, T& record) const {
    R given{};
    read(o.field(name_), given);
    const R expected = (record.*get_)();
    if (given != expected) {
      o.in().fail(std::string(name_) + " = " + nlohmann::json(given).dump() + " does not match " +
                  formula_ + " = " + nlohmann::json(expected).dump());
    }
  }
};

template <class T, class R>
constexpr Computed<T, R> computed(const char* name, R (T::*get)() const, const char* formula) {
  return {name, get, formula};
}

// A nested JSON object whose fields are members of the enclosing record itself.
template <class T, class Fields>
struct Group {
  const char* name_;
  Fields fields_;

  void write_into(nlohmann::json& j, const T& record) const {
    nlohmann::json inner = nlohmann::json::object();
    std::apply([&](const auto&... f) { (f.write_into(inner, record), ...); }, fields_);
    j[name_] = std::move(inner);
  }
  void read_from(ObjectIn& o, T& record) const {
    ObjectIn inner(o.field(name_));
    std::apply([&](const auto&... f) { (f.read_from(inner, record), ...); }, fields_);
    inner.finish();
  }
};

template <class First, class... Rest>
constexpr auto group(const char* name, First first, Rest... rest) {
  return Group<typename First::Record, std::tuple<First, Rest...>>{name,
                                                                   std::tuple{first, rest...}};
}

// Fields already listed elsewhere as an array of (name, member) pairs of one type, such as
// kMachineCostFields, which cost calibration also walks.
template <class T, class M, std::size_t N>
struct FieldList {
  std::array<std::pair<const char*, M T::*>, N> list_;

  void write_into(nlohmann::json& j, const T& record) const {
    for (const auto& [name, member] : list_) j[name] = to_json_value(record.*member);
  }
  void read_from(ObjectIn& o, T& record) const {
    for (const auto& [name, member] : list_) read(o.field(name), record.*member);
  }
};

template <class T, class M, std::size_t N>
constexpr FieldList<T, M, N> field_list(const std::array<std::pair<const char*, M T::*>, N>& list) {
  return {list};
}

namespace detail {
template <class T>
struct IsSequence : std::false_type {};
template <class T>
struct IsSequence<std::vector<T>> : std::true_type {};
template <class T, std::size_t N>
struct IsSequence<std::array<T, N>> : std::true_type {};
template <class T>
struct IsStringMap : std::false_type {};
template <class T>
struct IsStringMap<std::map<std::string, T>> : std::true_type {};
}  // namespace detail

template <class T>
nlohmann::json to_json_value(const T& value) {
  if constexpr (Described<T>) {
    nlohmann::json j = nlohmann::json::object();
    std::apply([&](const auto&... f) { (f.write_into(j, value), ...); }, FieldTable<T>::kFields);
    return j;
  } else if constexpr (detail::IsOptional<T>::value) {
    return value ? to_json_value(*value) : nlohmann::json(nullptr);
  } else if constexpr (detail::IsSequence<T>::value) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& item : value) j.push_back(to_json_value(item));
    return j;
  } else if constexpr (detail::IsStringMap<T>::value) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [key, item] : value) j[key] = to_json_value(item);
    return j;
  } else {
    return nlohmann::json(value);
  }
}

// A record is reset first, so that a field allowed to be absent keeps its default.
template <Described T>
void read_record(const JsonIn& in, T& out) {
  out = T{};
  ObjectIn o(in);
  std::apply([&](const auto&... f) { (f.read_from(o, out), ...); }, FieldTable<T>::kFields);
  o.finish();
  if constexpr (requires { FieldTable<T>::validate(in, out); }) FieldTable<T>::validate(in, out);
}

}  // namespace contactlab::tuner

namespace contactlab {

template <tuner::Described T>
void read(const JsonIn& in, T& out) {
  tuner::read_record(in, out);
}

}  // namespace contactlab
