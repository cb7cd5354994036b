// Writing output files without harming what is already there. Every file penumbra writes (images,
// reports, the reference cache) goes through replaceFile: the content is written to a new file
// beside the target, created exclusively (so never through a symbolic link, and never onto a file
// of another run), and renamed onto the target only once complete. An interrupted run therefore
// leaves the previous file or none at the final name, never a truncated one; a symbolic link at
// the target is replaced itself, its target left alone; a read-only file is refused, not replaced.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace penumbra {

// Writes `path` by calling `write(tempPath)` to fill a fresh file in the same folder, then renames
// it onto `path`. Throws Error naming `path` when the folder is not writable, the target is a
// folder or read-only, or `write` throws (the temporary file is removed).
void replaceFile(const std::string& path, const std::function<void(const std::string& tempPath)>& write);

// `name` as one safe file-name component: ASCII letters, digits, '-', '_' and '.' kept, every
// other byte (a path separator, NUL, '#', '?', '%', spaces, non-ASCII) becomes '_', runs of '_'
// collapse, leading dots and dashes are dropped (no hidden files, no options), at most 64 bytes;
// an empty result is "scene".
std::string fileNameSlug(std::string_view name);

// The identity of an existing file (device and inode), which survives other names for the same
// file (links, "./", relative and absolute paths); nullopt when it does not exist.
struct FileIdentity {
  unsigned long long device = 0, inode = 0;
  bool operator==(const FileIdentity&) const = default;
};
std::optional<FileIdentity> fileIdentity(const std::string& path);

}  // namespace penumbra
