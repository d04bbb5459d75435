// Files that a kill at any moment leaves whole (stac induct's state, model files): a replaced
// file goes through PATH.tmp, fsynced, renamed over PATH, its folder fsynced; an appended line is
// fsynced before the call returns, and a torn last line (a kill during an append, never
// acknowledged) is cut off before the next.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>

#include "rt/expected.hpp"

namespace stac::formats {

// `bytes` to `path` through PATH.tmp: written, fsynced, renamed over `path`, the folder fsynced.
rt::Status write_file_durably(const std::filesystem::path& path,
                              std::span<const std::uint8_t> bytes);
// Text (a report, a metrics file) to `path` the same way.
rt::Status write_text_durably(const std::filesystem::path& path, const std::string& text);
// One line (a '\n' is added) appended to `path` and fsynced before returning. A torn last line
// (a kill during an earlier append, never acknowledged) is cut off first.
rt::Status append_line_durably(const std::filesystem::path& path, const std::string& line);
// Cuts a torn last line (no '\n': a kill during an append) off `path`, if it exists.
rt::Status cut_torn_tail(const std::filesystem::path& path);
// A last line without its '\n' in a file people also write by hand (printf, echo -n and many
// editors end a file so): completed with the '\n' when `whole` says it is a whole record, cut
// off as torn otherwise. Returns whether a torn line was cut. With `complete` (e.g. "parses as a
// JSON value"): a line that is complete but not a whole record was written so by a person, not
// torn by a kill, and is an error naming the file and the line (the file is left as it is).
rt::Result<bool> complete_or_cut_tail(const std::filesystem::path& path,
                                      const std::function<bool(const std::string&)>& whole,
                                      const std::function<bool(const std::string&)>& complete = {});

}  // namespace stac::formats
