// Helpers shared by the tests that drive the `scoopsim` binary (SCOOPSIM_BINARY) end to end.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
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

}  // namespace scoopsim_test
