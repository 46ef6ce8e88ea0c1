// Helpers shared by the tests that drive the `scoopsim` binary (SCOOPSIM_BINARY) end to end.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace scoopsim_test {

// A folder of this test process, <tmp>/scoopsim_<tag>_<pid>, emptied at its first use.
inline std::filesystem::path ProcessTempDir(const std::string& tag) {
  namespace fs = std::filesystem;
  const fs::path p =
      fs::temp_directory_path() / ("scoopsim_" + tag + "_" + std::to_string(::getpid()));
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
