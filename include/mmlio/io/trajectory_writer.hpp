#pragma once
// Trajectory files: TUM (read + write) and KITTI (write + read) text formats, and the
// atomic write used by every output writer of io/.
//
// TUM:   one pose per line, `stamp tx ty tz qx qy qz qw`, stamp in seconds with exactly 9
//        decimals (printed from the integer nanoseconds, so no rounding), quaternion with
//        qw >= 0. Lines starting with '#' are comments. Readable by `evo_ape tum`.
// KITTI: one pose per line, the 12 numbers of the top 3x4 of T_world_body, row-major, no
//        stamps. KITTI keeps the stamps in a separate `times.txt` (one stamp in seconds per
//        line); writeKittiTimes writes that file, readKitti takes it optionally.
// Numbers are written in the shortest form that reads back to the same double.

#include <functional>
#include <ostream>
#include <string>

#include "mmlio/core/types.hpp"

namespace mmlio::io {

/// Writes through `write` into `<path>.tmp-<pid>` and renames it onto `path` once complete, so a
/// crash or an exception never leaves a half-written output. Throws mmlio::Error naming the path.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Shortest decimal text that parses back to exactly `value` ("0.1", "1e-09", "nan").
std::string formatDouble(double value);

/// Integer nanoseconds as seconds with exactly 9 decimals ("1673400472.138016708").
std::string formatStampSeconds(Stamp stamp_ns);
/// Parses a decimal seconds string without going through double when it is plain fixed-point
/// (so 9-decimal stamps round-trip exactly); falls back to double for exponent notation.
/// Returns false on malformed text.
bool parseStampSeconds(const std::string& text, Stamp& stamp_ns);

void writeTum(const std::string& path, const Trajectory& trajectory);
/// Throws mmlio::Error naming `file:line` on a malformed row (not 8 numbers, non-finite values,
/// zero-norm quaternion). Quaternions are normalised on read.
Trajectory readTum(const std::string& path);

/// KITTI poses file (12 numbers per line). Stamps are not part of the format: see writeKittiTimes.
void writeKitti(const std::string& path, const Trajectory& trajectory);
/// KITTI `times.txt`: one stamp per line, seconds with 9 decimals.
void writeKittiTimes(const std::string& path, const Trajectory& trajectory);
/// Reads a KITTI poses file; stamps come from `times_path` when given (line counts must match),
/// otherwise they are 0, 1, 2, ... ns (the pose index).
Trajectory readKitti(const std::string& path, const std::string& times_path = "");

}  // namespace mmlio::io
