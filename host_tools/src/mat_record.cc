#include "mjc/host/mat_record.h"

#include <matio.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "mjc/host/report.h"

namespace mjc::host {
namespace {

// One CSV record read back: its columns' names and cells, row by row.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
};

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

// The tools' CSV: note lines starting with '#', a header, rows of plain cells. A last
// row without its newline (its writer died in the middle of it) is left out.
bool ReadTable(const std::filesystem::path& path, Table* out, std::string* why) {
  const std::optional<std::string> read = ReadFileText(path);
  if (!read) {
    *why = "cannot read " + path.string();
    return false;
  }
  const std::string& text = *read;
  std::size_t start = 0;
  int number = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    if (end == std::string::npos) break;  // cut short: not a whole row
    std::string line = text.substr(start, end - start);
    start = end + 1;
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line.front() == '#') continue;
    std::vector<std::string> cells = Split(line);
    if (out->columns.empty()) {
      out->columns = std::move(cells);
      continue;
    }
    if (cells.size() != out->columns.size()) {
      *why = path.string() + ":" + std::to_string(number) + ": " +
             std::to_string(cells.size()) + " cells, the header has " +
             std::to_string(out->columns.size());
      return false;
    }
    out->rows.push_back(std::move(cells));
  }
  if (out->columns.empty()) {
    *why = path.string() + ": no header line";
    return false;
  }
  return true;
}

std::optional<double> Number(const std::string& cell) {
  if (cell.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  if (*end != '\0' || errno == ERANGE || !std::isfinite(v)) return std::nullopt;
  return v;
}

// A MATLAB name: a letter, then letters, digits and underscores, at most 63 of them.
bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > 63) return false;
  const auto letter = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
  };
  if (!letter(name.front())) return false;
  return std::all_of(name.begin(), name.end(), [&](char c) {
    return letter(c) || (c >= '0' && c <= '9') || c == '_';
  });
}

// libmatio's variables are C objects freed with Mat_VarFree (a struct frees its fields).
struct VarFree {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using Var = std::unique_ptr<matvar_t, VarFree>;

Var CharVar(const char* name, const std::string& text) {
  std::array<std::size_t, 2> dims{1, text.size()};
  return Var(Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UINT8, 2, dims.data(),
                           const_cast<char*>(text.data()), 0));
}

// A column as a struct's field: doubles when every cell is a number, else strings.
Var ColumnVar(const Table& t, std::size_t column) {
  const std::size_t n = t.rows.size();
  std::vector<double> values;
  values.reserve(n);
  for (const auto& row : t.rows) {
    const auto v = Number(row[column]);
    if (!v) break;
    values.push_back(*v);
  }
  const char* name = t.columns[column].c_str();
  std::array<std::size_t, 2> dims{n, 1};
  if (values.size() == n) {
    return Var(Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims.data(),
                             values.data(), 0));
  }
  Var cell(Mat_VarCreate(name, MAT_C_CELL, MAT_T_CELL, 2, dims.data(), nullptr, 0));
  if (!cell) return cell;
  for (std::size_t i = 0; i < n; ++i) {
    // The cell array takes each element over.
    Mat_VarSetCell(cell.get(), static_cast<int>(i),
                   CharVar(nullptr, t.rows[i][column]).release());
  }
  return cell;
}

Var StructVar(const char* name, const std::vector<std::string>& fields) {
  std::vector<const char*> names;
  for (const auto& f : fields) names.push_back(f.c_str());
  std::array<std::size_t, 2> dims{1, 1};
  return Var(Mat_VarCreateStruct(name, 2, dims.data(), names.data(),
                                 static_cast<unsigned>(names.size())));
}

}  // namespace

std::string UnitOfColumn(const std::string& column) {
  // Longest suffix first: _Nms_rad before _rad, _Nm_rad before _Nm.
  static const std::pair<const char*, const char*> kSuffixes[] = {
      {"_Nms_rad", "N*m*s/rad"},
      {"_Nm_rad", "N*m/rad"},
      {"_Nm", "N*m"},
      {"_rad_s", "rad/s"},
      {"_J", "J"},
      {"_W", "W"},
      {"_deg", "deg"},
      {"_rad", "rad"},
      {"_pct", "%"},
      {"_Hz", "Hz"},
      {"_ms", "ms"},
      {"_s", "s"}};
  for (const auto& [suffix, unit] : kSuffixes) {
    const std::string s = suffix;
    if (column.size() > s.size() &&
        column.compare(column.size() - s.size(), s.size(), s) == 0) {
      return unit;
    }
  }
  return "1";
}

bool WriteRunMat(const std::filesystem::path& dir, std::string* why) {
  // The records, in a fixed order (MATLAB lists variables as written).
  std::vector<std::filesystem::path> csvs, jsons;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const auto& p = entry.path();
    if (!entry.is_regular_file()) continue;
    if (p.extension() == ".csv") csvs.push_back(p);
    if (p.extension() == ".json") jsons.push_back(p);
  }
  if (error) {
    *why = "cannot list " + dir.string() + ": " + error.message();
    return false;
  }
  std::sort(csvs.begin(), csvs.end());
  std::sort(jsons.begin(), jsons.end());

  std::vector<Var> vars;
  std::vector<std::string> unit_fields;
  std::vector<Var> unit_structs;
  for (const auto& path : csvs) {
    const std::string name = path.stem().string();
    if (!ValidName(name)) continue;  // not one of the tools' records
    Table t;
    if (!ReadTable(path, &t, why)) return false;
    for (const auto& c : t.columns) {
      if (!ValidName(c)) {
        *why = path.string() + ": column '" + c + "' is not a MATLAB name";
        return false;
      }
    }
    Var record = StructVar(name.c_str(), t.columns);
    Var units = StructVar(name.c_str(), t.columns);
    if (!record || !units) {
      *why = "libmatio cannot make the struct " + name;
      return false;
    }
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      // The struct takes each field over.
      Mat_VarSetStructFieldByName(record.get(), t.columns[c].c_str(), 0,
                                  ColumnVar(t, c).release());
      Mat_VarSetStructFieldByName(units.get(), t.columns[c].c_str(), 0,
                                  CharVar(nullptr, UnitOfColumn(t.columns[c])).release());
    }
    vars.push_back(std::move(record));
    unit_fields.push_back(name);
    unit_structs.push_back(std::move(units));
  }
  if (!unit_fields.empty()) {
    Var units = StructVar("units", unit_fields);
    for (std::size_t i = 0; i < unit_fields.size(); ++i) {
      Mat_VarSetStructFieldByName(units.get(), unit_fields[i].c_str(), 0,
                                  unit_structs[i].release());
    }
    vars.push_back(std::move(units));
  }
  for (const auto& path : jsons) {
    const std::string name = path.stem().string() + "_json";
    if (!ValidName(name)) continue;
    const std::optional<std::string> text = ReadFileText(path);
    if (!text) {
      *why = "cannot read " + path.string();
      return false;
    }
    vars.push_back(CharVar(name.c_str(), *text));
  }

  const std::filesystem::path target = dir / "run.mat";
  const std::filesystem::path part = dir / "run.mat.part";
  mat_t* mat = Mat_CreateVer(part.c_str(), nullptr, MAT_FT_MAT5);
  if (mat == nullptr) {
    *why = "cannot write " + part.string();
    return false;
  }
  bool ok = true;
  for (const Var& v : vars) {
    if (!v || Mat_VarWrite(mat, v.get(), MAT_COMPRESSION_NONE) != 0) ok = false;
  }
  if (Mat_Close(mat) != 0) ok = false;
  if (!ok) {
    std::filesystem::remove(part, error);
    *why = "cannot write " + target.string() + " (libmatio)";
    return false;
  }
  std::filesystem::rename(part, target, error);
  if (error) {
    *why = "cannot write " + target.string() + ": " + error.message();
    return false;
  }
  return true;
}

}  // namespace mjc::host
