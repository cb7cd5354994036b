// Output files written beside their target and renamed into place (src/core/output_file.h).
#include "core/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "penumbra/error.h"

namespace penumbra {

namespace fs = std::filesystem;

void replaceFile(const std::string& path, const std::function<void(const std::string& tempPath)>& write) {
  const fs::path target(path);
  struct stat existing {};
  if (::lstat(path.c_str(), &existing) == 0) {
    if (S_ISDIR(existing.st_mode)) fail("cannot write '{}': it is a folder", path);
    // A read-only file is the user's statement that it must not change; a link is replaced itself
    // (rename does not follow it), so its target's permissions do not matter.
    // By its mode bits rather than access(), which says yes to root for any file.
    if (S_ISREG(existing.st_mode) && (existing.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0)
      fail(
          "cannot write '{}': the file exists and is read-only; penumbra does not replace it (remove it or choose "
          "another output folder)",
          path);
  }
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  // mkstemp creates the file with O_CREAT | O_EXCL: a new file, never an existing one or a link.
  std::string temp = (folder / ("." + target.filename().string() + ".partial-XXXXXX")).string();
  const int fd = ::mkstemp(temp.data());
  if (fd < 0)
    fail("cannot write '{}': cannot create a file in '{}' ({}; check that the folder exists and is writable)", path,
         folder.string(), std::strerror(errno));
  ::fchmod(fd, 0644);  // mkstemp makes it 0600; outputs are as readable as any other file
  ::close(fd);
  try {
    write(temp);
  } catch (...) {
    ::unlink(temp.c_str());
    throw;
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    fail("cannot write '{}': {}", path, std::strerror(err));
  }
}

std::string fileNameSlug(std::string_view name) {
  std::string out;
  for (const char c : name) {
    const bool keep =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.';
    const char k = keep ? c : '_';
    if (k == '_' && !out.empty() && out.back() == '_') continue;
    if ((k == '.' || k == '-') && out.empty()) continue;
    out += k;
    if (out.size() == 64) break;
  }
  // "." and ".." cannot survive the leading-dot rule; a name of only dots and dashes is empty here.
  return out.empty() ? std::string("scene") : out;
}

std::optional<FileIdentity> fileIdentity(const std::string& path) {
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0) return std::nullopt;
  return FileIdentity{static_cast<unsigned long long>(s.st_dev), static_cast<unsigned long long>(s.st_ino)};
}

}  // namespace penumbra
