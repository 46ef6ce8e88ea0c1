// Helpers shared by the tests that drive the `scoopsim` binary (SCOOPSIM_BINARY) end to end, and
// the tests' temporary folders (ProcessTempDir).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
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

}  // namespace scoopsim_test
