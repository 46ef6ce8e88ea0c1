// The clean-header file driver (sim/files/internal_h5.h, CleanHeaderDriver): POSIX I/O as HDF5's own
// sec2 driver, except that the superblock on disk always reads as a closed file. Why and what it
// guarantees: docs/files.md "Crash-safe output".
//
// HDF5 1.10 in SWMR mode writes the metadata of a dataset's appends in dependency order (a block
// is on disk before anything that points to it) and never reuses freed space, so every prefix of
// those writes is a consistent file (a new link in a group is one write too, as the output keeps
// a group's links in its header: GroupGcpl in sim/files/internal_h5.h); but it marks the superblock "open
// for writing" (file consistency flags), and a file killed in that state opens only in SWMR-read
// mode or after `h5clear`. This driver rewrites each superblock image on its way to disk:
//   - the consistency flags are cleared (plain readers open it as a closed file);
//   - its end-of-file address is at least the end of every write so far (a block written after
//     the superblock and pointed to by later metadata stays inside the file), and the file is
//     never shorter than that address (a reader refuses a file shorter than its superblock says).
// After a failed write (disk full, RLIMIT_FSIZE) the driver drops every later write, so the file
// stays the consistent prefix that was on disk: row counts are never ahead of the rows.
#include <fcntl.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "sim/files/internal_h5.h"

namespace sim::h5 {
namespace {

// Superblock version 2/3 with 8-byte addresses (what H5F_LIBVER_LATEST writes in 1.10): signature
// (8), version, sizeof offsets, sizeof lengths, consistency flags (1 each), base address,
// extension address, end-of-file address, root object header (8 each), checksum (4).
constexpr size_t kSuperblockSize = 48;
constexpr size_t kFlagsAt = 11;
constexpr size_t kEofAt = 28;
constexpr size_t kChecksumAt = 44;
constexpr unsigned char kSignature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};

uint32_t Rot(uint32_t x, int k) { return (x << k) ^ (x >> (32 - k)); }

// Bob Jenkins' lookup3 hashlittle, byte by byte, as HDF5's H5_checksum_lookup3 (initval 0 for
// metadata checksums).
uint32_t Lookup3(const unsigned char* k, size_t length) {
  uint32_t a, b, c;
  a = b = c = 0xdeadbeef + static_cast<uint32_t>(length);
  auto word = [](const unsigned char* p) {
    return p[0] + (uint32_t{p[1]} << 8) + (uint32_t{p[2]} << 16) + (uint32_t{p[3]} << 24);
  };
  while (length > 12) {
    a += word(k);
    b += word(k + 4);
    c += word(k + 8);
    // The mix of lookup3, as published.
    a -= c;
    a ^= Rot(c, 4);
    c += b;
    b -= a;
    b ^= Rot(a, 6);
    a += c;
    c -= b;
    c ^= Rot(b, 8);
    b += a;
    a -= c;
    a ^= Rot(c, 16);
    c += b;
    b -= a;
    b ^= Rot(a, 19);
    a += c;
    c -= b;
    c ^= Rot(b, 4);
    b += a;
    length -= 12;
    k += 12;
  }
  if (length == 0) return c;
  unsigned char tail[12] = {};
  std::memcpy(tail, k, length);
  a += word(tail);
  b += word(tail + 4);
  c += word(tail + 8);
  // The final mix of lookup3.
  c ^= b;
  c -= Rot(b, 14);
  a ^= c;
  a -= Rot(c, 11);
  b ^= a;
  b -= Rot(a, 25);
  c ^= b;
  c -= Rot(b, 16);
  a ^= c;
  a -= Rot(c, 4);
  b ^= a;
  b -= Rot(a, 14);
  c ^= b;
  c -= Rot(b, 24);
  return c;
}

uint64_t LoadLe64(const unsigned char* p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

void StoreLe(unsigned char* p, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i, v >>= 8) p[i] = static_cast<unsigned char>(v & 0xff);
}

bool IsSuperblock(const unsigned char* p, size_t size) {
  return size >= kSuperblockSize && std::memcmp(p, kSignature, 8) == 0 && p[8] >= 2 && p[9] == 8;
}

// The open file: the public part HDF5 reads first, then ours.
struct CleanFile {
  H5FD_t pub;
  int fd = -1;
  haddr_t eoa = 0;
  haddr_t eof = 0;  // physical size
  dev_t device = 0;
  ino_t inode = 0;
  unsigned char superblock[kSuperblockSize] = {};  // the image on disk, once written
  bool have_superblock = false;
  haddr_t superblock_eof = 0;  // end-of-file address in that image
  haddr_t written_end = 0;     // end of the furthest write
  CleanDriverState state;
};

CleanFile* Of(H5FD_t* f) { return reinterpret_cast<CleanFile*>(f); }
const CleanFile* Of(const H5FD_t* f) { return reinterpret_cast<const CleanFile*>(f); }

// Test hook: SCOOPSIM_H5_KILL_AT_WRITE=K SIGKILLs the process just before its K-th write to a
// file of this driver, so a test can kill a run between any two of its writes
// (tests/sim/run_output_test.cpp, KilledBeforeAnyWriteLeavesEverySnapshotReadable).
void KillHereIfAsked() {
  static const long kill_at = [] {
    const char* text = std::getenv("SCOOPSIM_H5_KILL_AT_WRITE");
    return text != nullptr ? std::atol(text) : 0L;
  }();
  static std::atomic<long> writes{0};
  if (kill_at > 0 && ++writes == kill_at) ::raise(SIGKILL);
}

bool WriteAll(int fd, const unsigned char* p, size_t size, haddr_t at, CleanFile* f) {
  KillHereIfAsked();
  while (size > 0) {
    const ssize_t n = ::pwrite(fd, p, size, static_cast<off_t>(at));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      f->state.failed = true;
      f->state.error = n < 0 ? errno : ENOSPC;
      return false;
    }
    p += n;
    at += static_cast<haddr_t>(n);
    size -= static_cast<size_t>(n);
  }
  return true;
}

// Makes the file at least `size` bytes long (zeros).
bool GrowTo(CleanFile* f, haddr_t size) {
  if (f->eof >= size) return true;
  if (::ftruncate(f->fd, static_cast<off_t>(size)) != 0) {
    f->state.failed = true;
    f->state.error = errno;
    return false;
  }
  f->eof = size;
  f->state.file_size = size;
  return true;
}

// Writes the superblock image with clean flags and end-of-file address `eof`.
bool WriteSuperblock(CleanFile* f, haddr_t eof) {
  unsigned char* s = f->superblock;
  s[kFlagsAt] = 0;
  StoreLe(s + kEofAt, eof, 8);
  StoreLe(s + kChecksumAt, Lookup3(s, kChecksumAt), 4);
  if (!GrowTo(f, eof)) return false;
  if (!WriteAll(f->fd, s, kSuperblockSize, 0, f)) return false;
  f->superblock_eof = eof;
  return true;
}

H5FD_t* Open(const char* name, unsigned flags, hid_t /*fapl*/, haddr_t maxaddr) {
  if (name == nullptr || maxaddr == 0 || maxaddr == HADDR_UNDEF) return nullptr;
  int o_flags = (flags & H5F_ACC_RDWR) ? O_RDWR : O_RDONLY;
  if (flags & H5F_ACC_TRUNC) o_flags |= O_TRUNC;
  if (flags & H5F_ACC_CREAT) o_flags |= O_CREAT;
  if (flags & H5F_ACC_EXCL) o_flags |= O_EXCL;
  const int fd = ::open(name, o_flags | O_CLOEXEC, 0666);
  if (fd < 0) return nullptr;
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    ::close(fd);
    return nullptr;
  }
  auto* f = new CleanFile;
  f->fd = fd;
  f->eof = static_cast<haddr_t>(st.st_size);
  f->state.file_size = f->eof;
  f->written_end = f->eof;
  f->device = st.st_dev;
  f->inode = st.st_ino;
  return &f->pub;
}

herr_t Close(H5FD_t* file) {
  CleanFile* f = Of(file);
  const int status = ::close(f->fd);
  delete f;
  return status == 0 ? 0 : -1;
}

int Compare(const H5FD_t* a, const H5FD_t* b) {
  const CleanFile* x = Of(a);
  const CleanFile* y = Of(b);
  if (x->device != y->device) return x->device < y->device ? -1 : 1;
  if (x->inode != y->inode) return x->inode < y->inode ? -1 : 1;
  return 0;
}

herr_t Query(const H5FD_t* /*file*/, unsigned long* flags) {
  // As sec2, less metadata accumulation and sieving: every write goes out when HDF5 issues it,
  // in HDF5's order.
  *flags = H5FD_FEAT_AGGREGATE_METADATA | H5FD_FEAT_AGGREGATE_SMALLDATA |
           H5FD_FEAT_POSIX_COMPAT_HANDLE | H5FD_FEAT_SUPPORTS_SWMR_IO |
           H5FD_FEAT_DEFAULT_VFD_COMPATIBLE;
  return 0;
}

haddr_t GetEoa(const H5FD_t* file, H5FD_mem_t /*type*/) { return Of(file)->eoa; }

herr_t SetEoa(H5FD_t* file, H5FD_mem_t /*type*/, haddr_t addr) {
  Of(file)->eoa = addr;
  return 0;
}

haddr_t GetEof(const H5FD_t* file, H5FD_mem_t /*type*/) { return Of(file)->eof; }

herr_t GetHandle(H5FD_t* file, hid_t /*fapl*/, void** handle) {
  *handle = &Of(file)->fd;
  return 0;
}

herr_t Read(H5FD_t* file, H5FD_mem_t /*type*/, hid_t /*dxpl*/, haddr_t addr, size_t size,
            void* buffer) {
  CleanFile* f = Of(file);
  auto* p = static_cast<unsigned char*>(buffer);
  while (size > 0) {
    const ssize_t n = ::pread(f->fd, p, size, static_cast<off_t>(addr));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return -1;
    if (n == 0) {  // past the end of the file: zeros, as sec2
      std::memset(p, 0, size);
      break;
    }
    p += n;
    addr += static_cast<haddr_t>(n);
    size -= static_cast<size_t>(n);
  }
  return 0;
}

herr_t Write(H5FD_t* file, H5FD_mem_t /*type*/, hid_t /*dxpl*/, haddr_t addr, size_t size,
             const void* buffer) {
  CleanFile* f = Of(file);
  // After a failed write the file stays as it was: later writes are dropped, reported as done so
  // that the library can still close the file (a close that fails leaves HDF5 half shut down).
  if (f->state.failed) return 0;
  const auto* p = static_cast<const unsigned char*>(buffer);
  const haddr_t end = addr + size;
  if (addr == 0 && IsSuperblock(p, size)) {
    // The library's superblock: clean flags, and an end no smaller than any write so far.
    std::memcpy(f->superblock, p, kSuperblockSize);
    f->have_superblock = true;
    const haddr_t eof = std::max(LoadLe64(p + kEofAt), f->written_end);
    if (!WriteSuperblock(f, eof)) return -1;
    if (size > kSuperblockSize &&
        !WriteAll(f->fd, p + kSuperblockSize, size - kSuperblockSize, kSuperblockSize, f))
      return -1;
  } else if (!WriteAll(f->fd, p, size, addr, f)) {
    return -1;
  }
  f->eof = std::max(f->eof, end);
  f->state.file_size = f->eof;
  f->written_end = std::max(f->written_end, end);
  // A block past the superblock's end: move the end, so whatever points here later is inside.
  if (f->have_superblock && end > f->superblock_eof && !WriteSuperblock(f, end)) return -1;
  return 0;
}

herr_t Flush(H5FD_t* /*file*/, hid_t /*dxpl*/, hbool_t /*closing*/) { return 0; }

herr_t Truncate(H5FD_t* file, hid_t /*dxpl*/, hbool_t /*closing*/) {
  CleanFile* f = Of(file);
  if (f->state.failed) return 0;  // as Write
  // To the allocated size, as sec2, but never below the end the superblock on disk names.
  const haddr_t size = std::max(f->eoa, f->superblock_eof);
  if (size == f->eof) return 0;
  if (::ftruncate(f->fd, static_cast<off_t>(size)) != 0) {
    f->state.failed = true;
    f->state.error = errno;
    return -1;
  }
  f->eof = size;
  f->state.file_size = size;
  return 0;
}

herr_t Lock(H5FD_t* file, hbool_t rw) {
  if (::flock(Of(file)->fd, (rw ? LOCK_EX : LOCK_SH) | LOCK_NB) == 0 || errno == ENOSYS) return 0;
  return -1;
}

herr_t Unlock(H5FD_t* file) {
  if (::flock(Of(file)->fd, LOCK_UN) == 0 || errno == ENOSYS) return 0;
  return -1;
}

H5FD_class_t MakeClass() {
  H5FD_class_t c{};
  c.name = "scoopsim_clean_header";
  c.maxaddr = (haddr_t{1} << 62);
  c.fc_degree = H5F_CLOSE_STRONG;
  c.open = Open;
  c.close = Close;
  c.cmp = Compare;
  c.query = Query;
  c.get_eoa = GetEoa;
  c.set_eoa = SetEoa;
  c.get_eof = GetEof;
  c.get_handle = GetHandle;
  c.read = Read;
  c.write = Write;
  c.flush = Flush;
  c.truncate = Truncate;
  c.lock = Lock;
  c.unlock = Unlock;
  const H5FD_mem_t map[H5FD_MEM_NTYPES] = H5FD_FLMAP_DICHOTOMY;
  std::copy(map, map + H5FD_MEM_NTYPES, c.fl_map);
  return c;
}

}  // namespace

hid_t CleanHeaderDriver() {
  static const H5FD_class_t cls = MakeClass();
  static const hid_t id = H5FDregister(&cls);
  return id;
}

const CleanDriverState* CleanDriverStateOf(hid_t file) {
  // H5Fget_vfd_handle gives the driver's handle, the descriptor inside our CleanFile: the
  // CleanFile holding it is found from its address. Only for files of this driver.
  const hid_t fapl = H5Fget_access_plist(file);
  if (fapl < 0) return nullptr;
  const hid_t driver = H5Pget_driver(fapl);
  H5Pclose(fapl);
  void* handle = nullptr;
  if (driver != CleanHeaderDriver() || H5Fget_vfd_handle(file, H5P_DEFAULT, &handle) < 0 ||
      handle == nullptr)
    return nullptr;
  const auto* f = reinterpret_cast<const CleanFile*>(static_cast<const char*>(handle) -
                                                     offsetof(CleanFile, fd));
  return &f->state;
}

}  // namespace sim::h5
