// Helpers shared by the tests that drive the `scoopsim` binary (SCOOPSIM_BINARY) end to end, and
// the tests' temporary folders (ProcessTempDir).
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace scoopsim_test {

// True when the user asked to keep the tests' files: SCOOPSIM_KEEP_TEST_FILES set, not "" or "0".
inline bool KeepTestFiles() {
  const char* keep = std::getenv("SCOOPSIM_KEEP_TEST_FILES");
  return keep != nullptr && *keep != '\0' && std::string(keep) != "0";
}

// The folders ProcessTempDir made, removed when the process that made them exits normally,
// passed or failed (a forked child leaving by exit() removes nothing); kept, and named on
// stderr, with SCOOPSIM_KEEP_TEST_FILES=1. A failed run names what it removed.
class TempDirs {
 public:
  static TempDirs& Get() {
    static TempDirs dirs;
    return dirs;
  }
  void Add(const std::filesystem::path& dir) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (std::find(dirs_.begin(), dirs_.end(), dir) == dirs_.end()) dirs_.push_back(dir);
  }
  ~TempDirs() {
    if (::getpid() != owner_) return;
    const bool keep = KeepTestFiles();
    const bool failed = ::testing::UnitTest::GetInstance()->Failed();
    for (const std::filesystem::path& dir : dirs_) {
      if (keep) {
        std::fprintf(stderr, "test files kept in %s\n", dir.c_str());
        continue;
      }
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
      if (failed) {
        std::fprintf(stderr, "test files removed from %s (SCOOPSIM_KEEP_TEST_FILES=1 keeps them)\n",
                     dir.c_str());
      }
    }
  }

 private:
  // The test program outlives this registry: made first, it is destroyed after it.
  TempDirs() : owner_(::getpid()) { ::testing::UnitTest::GetInstance(); }
  pid_t owner_;
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};

// A folder of this test process, $TMPDIR (else /tmp)/scoopsim_<tag>_<pid>, emptied at each call
// and removed when the process exits (TempDirs).
inline std::filesystem::path ProcessTempDir(const std::string& tag) {
  namespace fs = std::filesystem;
  const fs::path p =
      fs::temp_directory_path() / ("scoopsim_" + tag + "_" + std::to_string(::getpid()));
  TempDirs::Get().Add(p);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// Runs `scoopsim ARGS` with stderr sent to `stderr_file`; returns its exit status, -1 if it did
// not exit normally.
inline int RunScoopsim(const std::string& args, const std::string& stderr_file = "/dev/null") {
  const std::string cmd = std::string(SCOOPSIM_BINARY) + " " + args + " 2>" + stderr_file;
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The scenes the repository ships: the paths listed in `scenes_dir`/shipped.txt (one a line,
// relative to scenes_dir; '#' starts a comment), in the list's order. Tests walk these, never the
// folder, so a user's own scene left in scenes/ is not tested. Empty when the list is missing.
inline std::vector<std::filesystem::path> ShippedScenes(const std::filesystem::path& scenes_dir) {
  std::vector<std::filesystem::path> scenes;
  std::ifstream in(scenes_dir / "shipped.txt");
  for (std::string line; std::getline(in, line);) {
    line = line.substr(0, line.find('#'));
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    line = line.substr(first, line.find_last_not_of(" \t\r") - first + 1);
    scenes.push_back(scenes_dir / line);
  }
  return scenes;
}

// The whole text of a file ("" if it cannot be read).
inline std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Waits for a child; its exit status, or 128 + the signal that ended it.
inline int Wait(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Takes the write lock that scoopsim's writers take on an output file (an open-file-description
// lock, fcntl F_OFD_SETLK: sim/files/h5_output.h), as a process writing `path` holds it: the
// descriptor (closing it releases the lock), or -1 when the lock cannot be had.
inline int HoldOutputLock(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  struct flock lock {};
  lock.l_type = F_WRLCK;
  lock.l_whence = SEEK_SET;
  if (fd >= 0 && ::fcntl(fd, F_OFD_SETLK, &lock) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Paths made in `dir` that no output may replace, each with the word scoopsim's refusal uses:
// a FIFO (mkfifo works unprivileged) and, where mknod is allowed (root), a character device
// with /dev/null's numbers.
inline std::vector<std::pair<std::string, std::string>> SpecialFiles(
    const std::filesystem::path& dir) {
  std::vector<std::pair<std::string, std::string>> made;
  const std::string fifo = (dir / "fifo").string();
  if (::mkfifo(fifo.c_str(), 0644) == 0) made.emplace_back(fifo, "a FIFO (named pipe)");
  const std::string device = (dir / "device").string();
  if (::mknod(device.c_str(), S_IFCHR | 0644, makedev(1, 3)) == 0)
    made.emplace_back(device, "a character device");
  return made;
}

// A tmpfs of `size` bytes ("64k") mounted on the folder `dir` (made) while this lives: a full
// disk in miniature. Where mounting is not allowed (not root, a container without
// CAP_SYS_ADMIN) mounted() is false and error() says why: the test skips with a message.
class ScopedTmpfs {
 public:
  ScopedTmpfs(const std::filesystem::path& dir, const std::string& size) : dir_(dir) {
    std::filesystem::create_directories(dir);
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
    if (!mounted_) error_ = std::strerror(errno);
  }
  ~ScopedTmpfs() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  ScopedTmpfs(const ScopedTmpfs&) = delete;
  ScopedTmpfs& operator=(const ScopedTmpfs&) = delete;
  bool mounted() const { return mounted_; }
  const std::string& error() const { return error_; }

 private:
  std::filesystem::path dir_;
  bool mounted_ = false;
  std::string error_;
};

// The files in `dir` whose names end in one of the temporary suffixes scoopsim's writers use
// (.tmp, .partial, .new, .probe): none may be left after a failed write.
inline std::vector<std::string> TemporaryFiles(const std::filesystem::path& dir) {
  std::vector<std::string> left;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".tmp" || ext == ".partial" || ext == ".new" || ext == ".probe")
      left.push_back(entry.path().filename().string());
  }
  return left;
}

}  // namespace scoopsim_test
