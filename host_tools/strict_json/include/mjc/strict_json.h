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
#include <vector>

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

// A SAX handler (Json::sax_parse) that finds the first key an object repeats: JSON
// leaves a repeated key's meaning open, and nlohmann's parser keeps the last value
// without a word, so a file saying c_right_deg twice would be read as whichever came
// last. `duplicate` gets its dotted name ("cable.alpha"); the parse stops there.
template <class Json>
class DuplicateKeyCheck {
 public:
  std::string duplicate;

  bool null() { return Value(); }
  bool boolean(bool) { return Value(); }
  bool number_integer(typename Json::number_integer_t) { return Value(); }
  bool number_unsigned(typename Json::number_unsigned_t) { return Value(); }
  bool number_float(typename Json::number_float_t, const typename Json::string_t&) {
    return Value();
  }
  bool string(typename Json::string_t&) { return Value(); }
  bool binary(typename Json::binary_t&) { return Value(); }
  bool start_object(std::size_t) {
    levels_.push_back({true, {}, NameOfValue()});
    return true;
  }
  bool key(typename Json::string_t& k) {
    Level& level = levels_.back();
    for (const std::string& seen : level.keys) {
      if (seen == k) {
        duplicate = FieldName(level.name, k);
        return false;
      }
    }
    level.keys.push_back(k);
    return true;
  }
  bool end_object() { return End(); }
  bool start_array(std::size_t) {
    levels_.push_back({false, {}, NameOfValue()});
    return true;
  }
  bool end_array() { return End(); }
  bool parse_error(std::size_t, const std::string&, const typename Json::exception&) {
    return false;
  }

 private:
  struct Level {
    bool object;
    std::vector<std::string> keys;  // an object's keys so far (few: a linear search)
    std::string name;               // its dotted name ("" at the top)
  };
  std::vector<Level> levels_;
  // The dotted name of the value that starts now: its key's, or its array's name.
  std::string NameOfValue() const {
    if (levels_.empty()) return "";
    const Level& l = levels_.back();
    return l.object ? FieldName(l.name, l.keys.back()) : l.name;
  }
  bool Value() { return true; }
  bool End() {
    levels_.pop_back();
    return true;
  }
};

// The text of a file whose top level is an object, parsed; std::runtime_error
// "<source>: not valid JSON: …" (syntax, data after the value, or a number a double
// cannot hold), "<source>: key 'a.b' appears twice" or "<source>: the top level must be
// an object".
template <class Json>
Json ParseObject(std::string_view text, std::string_view source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const typename Json::exception& e) {
    throw std::runtime_error(std::string(source) + ": not valid JSON: " + e.what());
  }
  DuplicateKeyCheck<Json> check;
  if (!Json::sax_parse(text, &check) && !check.duplicate.empty()) {
    throw std::runtime_error(std::string(source) + ": key '" + check.duplicate +
                             "' appears twice (which one was meant?)");
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
