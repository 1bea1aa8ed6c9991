// The policy every JSON file the project reads follows (calibration files, run.json,
// mjc's config file, the plant's parameter sets): a key the reader does not know is an
// error that names it and the known key it most resembles, since a misspelt key that
// is silently ignored leaves its value at a default nobody chose. Also the "did you
// mean" of mjc's command line. Header and a small library of its own, free of the
// host tools' other dependencies, so the simulator's loaders share it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace mjc::strict {

// Edits (insertion, deletion, substitution, transposition of neighbours) from a to b:
// the optimal string alignment distance, so "c_rigth" is one edit from "c_right".
std::size_t EditDistance(std::string_view a, std::string_view b);

// The entry of `known` nearest `typed`, when it is near enough to be a slip: at most
// one edit for names of up to four characters, else at most a third of the longer
// name's length (rounded up, at most 3). nullopt otherwise or when `known` is empty;
// of equally near entries, the first.
std::optional<std::string_view> Closest(std::string_view typed,
                                        std::span<const std::string_view> known);

// "unknown key 'c_rigth_deg' (did you mean 'c_right_deg'?)", or, with nothing near,
// "unknown key 'x' (known: a, b, c)". `prefix` ("cable.") is put before both names.
std::string UnknownKeyMessage(std::string_view key,
                              std::span<const std::string_view> known,
                              std::string_view prefix = "");

// The message for the first key of `object` (any nlohmann::basic_json object) that is
// not in `known`; nullopt when every key is known or `object` is not an object.
template <class Json>
std::optional<std::string> UnknownKey(const Json& object,
                                      std::span<const std::string_view> known,
                                      std::string_view prefix = "") {
  if (!object.is_object()) return std::nullopt;
  for (const auto& item : object.items()) {
    bool found = false;
    for (const std::string_view k : known) found = found || k == item.key();
    if (!found) return UnknownKeyMessage(item.key(), known, prefix);
  }
  return std::nullopt;
}

// A field's dotted name in its file: "cable.alpha" (no prefix: the key alone).
inline std::string FieldName(std::string_view prefix, std::string_view key) {
  return prefix.empty() ? std::string(key) : std::string(prefix) + "." + std::string(key);
}

// The member `key` of `object`, or null when it has none.
template <class Json>
const Json* Member(const Json& object, std::string_view key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

// The text of a file whose top level is an object, parsed; std::runtime_error
// "<source>: not valid JSON: …" (syntax, or a number a double cannot hold) or "<source>:
// the top level must be an object".
template <class Json>
Json ParseObject(std::string_view text, std::string_view source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const typename Json::exception& e) {
    throw std::runtime_error(std::string(source) + ": not valid JSON: " + e.what());
  }
  if (!root.is_object()) {
    throw std::runtime_error(std::string(source) + ": the top level must be an object");
  }
  return root;
}

// The fields of one file (`source` names it in messages), read strictly: a field that is
// missing or of another type, or a section with a key the reader does not know, throws
// std::runtime_error "<source>: field '<dotted name>' <what>" (or "<source>: unknown key
// …"). `prefix` is the dotted name of the object a field is read from ("" at the top).
// Json is any nlohmann::basic_json (the parameter sets keep their keys' order).
template <class Json>
class FieldReader {
 public:
  explicit FieldReader(std::string_view source) : source_(source) {}

  [[noreturn]] void Fail(std::string_view field, const std::string& what) const {
    throw std::runtime_error(std::string(source_) + ": field '" + std::string(field) +
                             "' " + what);
  }

  // Every key of `object` must be in `known` (prefix: "cable." before the names).
  void CheckKnown(const Json& object, std::string_view prefix,
                  std::span<const std::string_view> known) const {
    if (const auto unknown = UnknownKey(object, known, prefix)) {
      throw std::runtime_error(std::string(source_) + ": " + *unknown);
    }
  }

  // The object `key` of the top level, every key of it in `known`.
  const Json& Section(const Json& root, std::string_view key,
                      std::span<const std::string_view> known) const {
    const Json& section = Value(root, "", key);
    if (!section.is_object()) Fail(key, "must be an object");
    CheckKnown(section, std::string(key) + ".", known);
    return section;
  }

  // The member `key` as it is, of any type (null too).
  const Json& Value(const Json& object, std::string_view prefix,
                    std::string_view key) const {
    const Json* v = Member(object, key);
    if (v == nullptr) Fail(FieldName(prefix, key), "is missing");
    return *v;
  }

  double Double(const Json& object, std::string_view prefix, std::string_view key) const {
    const Json& v = Value(object, prefix, key);
    if (!v.is_number()) Fail(FieldName(prefix, key), "must be a number");
    return v.template get<double>();
  }

  // An integer within [lo, hi].
  std::int64_t Integer(const Json& object, std::string_view prefix, std::string_view key,
                       std::int64_t lo, std::int64_t hi) const {
    const Json& v = Value(object, prefix, key);
    const std::string name = FieldName(prefix, key);
    if (!v.is_number_integer()) Fail(name, "must be an integer");
    const bool too_big = v.is_number_unsigned() &&
                         v.template get<std::uint64_t>() > static_cast<std::uint64_t>(hi);
    if (too_big || v.template get<std::int64_t>() < lo ||
        v.template get<std::int64_t>() > hi) {
      Fail(name, "= " + v.dump() + " is outside [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
    }
    return v.template get<std::int64_t>();
  }

  std::uint64_t Unsigned64(const Json& object, std::string_view prefix,
                           std::string_view key) const {
    const Json& v = Value(object, prefix, key);
    if (!v.is_number_unsigned())
      Fail(FieldName(prefix, key), "must be a non-negative integer");
    return v.template get<std::uint64_t>();
  }

  bool Bool(const Json& object, std::string_view prefix, std::string_view key) const {
    const Json& v = Value(object, prefix, key);
    if (!v.is_boolean()) Fail(FieldName(prefix, key), "must be true or false");
    return v.template get<bool>();
  }

  std::string String(const Json& object, std::string_view prefix,
                     std::string_view key) const {
    const Json& v = Value(object, prefix, key);
    if (!v.is_string()) Fail(FieldName(prefix, key), "must be a string");
    return v.template get<std::string>();
  }

 private:
  std::string_view source_;
};

}  // namespace mjc::strict
