#include "mjc/strict_json.h"

#include <algorithm>
#include <vector>

namespace mjc::strict {

std::size_t EditDistance(std::string_view a, std::string_view b) {
  // d[i][j]: edits from a's first i characters to b's first j, three rows kept.
  const std::size_t m = b.size();
  std::vector<std::size_t> before(m + 1), previous(m + 1), row(m + 1);
  for (std::size_t j = 0; j <= m; ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    row[0] = i;
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t substitution = previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      row[j] = std::min({previous[j] + 1, row[j - 1] + 1, substitution});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        row[j] = std::min(row[j], before[j - 2] + 1);
      }
    }
    before.swap(previous);
    previous.swap(row);
  }
  return previous[m];
}

std::optional<std::string_view> Closest(std::string_view typed,
                                        std::span<const std::string_view> known) {
  std::optional<std::string_view> best;
  std::size_t best_distance = 0;
  for (const std::string_view k : known) {
    const std::size_t longer = std::max(typed.size(), k.size());
    const std::size_t allowed =
        longer <= 4 ? 1 : std::min<std::size_t>(3, (longer + 2) / 3);
    const std::size_t d = EditDistance(typed, k);
    if (d <= allowed && (!best || d < best_distance)) {
      best = k;
      best_distance = d;
    }
  }
  return best;
}

std::string UnknownKeyMessage(std::string_view key,
                              std::span<const std::string_view> known,
                              std::string_view prefix) {
  std::string out = "unknown key '" + std::string(prefix) + std::string(key) + "'";
  if (const auto near = Closest(key, known)) {
    return out + " (did you mean '" + std::string(prefix) + std::string(*near) + "'?)";
  }
  out += " (known: ";
  for (std::size_t i = 0; i < known.size(); ++i) {
    out += (i ? ", " : "") + std::string(prefix) + std::string(known[i]);
  }
  return out + ")";
}

}  // namespace mjc::strict
