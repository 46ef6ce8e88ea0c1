// A byte archive of plain values, vectors of them and strings: one function lists a state's fields
// once, and runs over an ArchiveWriter to save them or an ArchiveReader to load them back
// (System::SaveState, the run checkpoints of sim/). Each vector carries its element size and
// length, so a reader of another layout fails with a message instead of reading garbage.
// Public header of the dem module.
#pragma once

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace dem {

class ArchiveWriter {
 public:
  template <typename T>
  void operator()(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    Append(&value, sizeof(T));
  }
  template <typename T>
  void operator()(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>, "vectors of plain values only");
    const uint64_t header[2] = {sizeof(T), values.size()};
    Append(header, sizeof header);
    if (!values.empty()) Append(values.data(), values.size() * sizeof(T));
  }
  void operator()(const std::string& text) { (*this)(std::vector<char>(text.begin(), text.end())); }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  void Append(const void* p, size_t n) {
    const char* c = static_cast<const char*>(p);
    bytes_.insert(bytes_.end(), c, c + n);
  }
  std::vector<char> bytes_;
};

class ArchiveReader {
 public:
  explicit ArchiveReader(const std::vector<char>& bytes) : bytes_(bytes) {}
  template <typename T>
  void operator()(T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "plain values only");
    Take(&value, sizeof(T));
  }
  template <typename T>
  void operator()(std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>, "vectors of plain values only");
    uint64_t header[2];
    Take(header, sizeof header);
    if (header[0] != sizeof(T) || header[1] > (bytes_.size() - at_) / sizeof(T))
      throw std::runtime_error("state archive: a field of another layout");
    values.resize(header[1]);
    if (!values.empty()) Take(values.data(), values.size() * sizeof(T));
  }
  void operator()(std::string& text) {
    std::vector<char> chars;
    (*this)(chars);
    text.assign(chars.begin(), chars.end());
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  void Take(void* p, size_t n) {
    if (n > bytes_.size() - at_) throw std::runtime_error("state archive: truncated");
    std::memcpy(p, bytes_.data() + at_, n);
    at_ += n;
  }
  const std::vector<char>& bytes_;
  size_t at_ = 0;
};

}  // namespace dem
