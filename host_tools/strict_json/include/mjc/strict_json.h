// The policy every JSON file the project reads follows (calibration files, run.json,
// mjc's config file, the plant's parameter sets): a key the reader does not know is an
// error that names it and the known key it most resembles, since a misspelt key that
// is silently ignored leaves its value at a default nobody chose. Also the "did you
// mean" of mjc's command line. Header and a small library of its own, free of the
// host tools' other dependencies, so the simulator's loaders share it.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
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

}  // namespace mjc::strict
