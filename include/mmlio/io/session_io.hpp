#pragma once
// The session folder (`OUT/session/`, docs/session.md): what a run leaves for a later run to
// localize in and extend. Text where a person may look (session.yaml, rig.yaml, keyframes.txt,
// loops.txt, keyframes.tum for evo), binary PCD for the clouds and the map (CloudCompare reads
// them). Numbers are written so that they read back to the same double: a session loaded and
// saved again is the same bytes.
#include <string>

#include "mmlio/core/session.hpp"

namespace mmlio::io {

inline constexpr int kSessionFormatVersion = 1;

/// What a session says about the run that made it.
struct SessionInfo {
  int format_version = kSessionFormatVersion;
  std::string mmlio_version, commit;
  std::string mode;      // hvi | vi | hi
  std::string rig_yaml;  // the run's effective config (rig.yaml), extrinsics included
};

/// Writes the session into `dir` (created or replaced as a whole: the files are written into a
/// folder beside it, which then takes its place, so a crash leaves the old session or the new one).
/// Throws mmlio::Error naming the path.
void writeSession(const std::string& dir, const Session& session, const SessionInfo& info);

/// Reads a session written by writeSession. Throws mmlio::Error in one line naming the file on a
/// missing or malformed file, another format version, or files that disagree (counts, indices).
Session readSession(const std::string& dir, SessionInfo* info = nullptr);

/// Whether `out_dir` (an existing folder) is the one that holds the session at `session_dir`, i.e. the
/// run that wrote it: a localization writing there would replace that run's trajectory and report.
bool holdsSession(const std::string& out_dir, const std::string& session_dir);

}  // namespace mmlio::io
