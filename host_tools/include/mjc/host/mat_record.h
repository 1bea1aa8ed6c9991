// A run folder's records as one MATLAB file (run.mat), for a lab that analyses in
// MATLAB: written from the folder's own files, so it says exactly what they say.
//
//   - each CSV record (windows.csv of mjc trial, sweep.csv of mjc calibrate) becomes a
//     struct named after the file, one field per column: a column vector of doubles, or
//     a cell array of strings for a column of words (windows.motion);
//   - `units`: a struct of those structs' field names, each holding its unit, read
//     from the column's name as the tools spell it (loading_J: "J", peak_torque_Nm:
//     "N*m", stiffness_Nm_rad: "N*m/rad", eta_pct: "%"; "1" for a count or a flag);
//   - each JSON record (run.json, calibration.json) as its text, in a char variable
//     named after the file (run_json): MATLAB's jsondecode reads it.
//
// The MAT-file is version 5 (libmatio, Debian's libmatio-dev), which MATLAB, Octave and
// scipy.io.loadmat read. It is written beside the records and renamed into place, so a
// process killed meanwhile leaves the previous one or none.
#pragma once

#include <filesystem>
#include <string>

namespace mjc::host {

// Writes dir/run.mat from dir's records (see above); false with the reason, naming the
// file and the line, when a record cannot be read or the file cannot be written.
bool WriteRunMat(const std::filesystem::path& dir, std::string* why);

// The unit the tools' spelling of a column name carries ("loading_J" → "J"); "1" when
// it carries none.
std::string UnitOfColumn(const std::string& column);

}  // namespace mjc::host
