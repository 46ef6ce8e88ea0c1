// sim::InputError: the one exception for bad user input, thrown by every room that reads a file
// or a value a user gave (scene, materials, mesh, URDF, bed, sweep, table, CLI).
#pragma once

#include <stdexcept>
#include <string>

namespace sim {

// Bad user input (scene, materials file, mesh or bed file, CLI value). what() is the one-line
// message to print; the CLI exits with status 2. An error about one value carries it as data:
// the file, the line (1-based; 0 when the file has no lines to speak of, like a mesh), the key
// (a scene's dotted path "dig.trajectory.moves[2].rate", or a field's own name), what was
// expected and what was there, so that a caller can report it under its own key without reading
// the text back. An error made from a bare message (a file that cannot be opened) has only what().
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
  // what() = "FILE:LINE: KEY: expected EXPECTED, got GOT (NOTE)", leaving out ":LINE" when line is
  // 0, "KEY: " when key is empty and " (NOTE)" when note is.
  InputError(std::string file, int line, std::string key, std::string expected, std::string got,
             std::string note = "");

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }
  const std::string& expected() const { return expected_; }
  const std::string& got() const { return got_; }
  const std::string& note() const { return note_; }

 private:
  std::string file_;
  int line_ = 0;
  std::string key_, expected_, got_, note_;
};

}  // namespace sim
