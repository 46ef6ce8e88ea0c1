// Internal to sim/ (not a public header): RAII handles and helpers over the HDF5 C API shared by
// the run output (h5_output.cpp) and the bed files (bed_io.cpp). Implemented in h5_output.cpp.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <string>
#include <vector>

#include "dem/system.h"

namespace sim::h5 {

// Owns one HDF5 identifier and closes it with the matching H5xclose on destruction.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_), closer_(o.closer_) { o.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      closer_ = o.closer_;
      o.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now; returns the close status (0 when there was nothing to close).
  herr_t reset() {
    herr_t status = 0;
    if (id_ >= 0 && closer_ != nullptr) status = closer_(id_);
    id_ = H5I_INVALID_HID;
    return status;
  }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

// Throw std::runtime_error("HDF5: <what> failed") when an HDF5 call reports failure (< 0).
hid_t CheckId(hid_t id, const std::string& what);
void CheckOk(herr_t status, const std::string& what);

// Creates the parent folders of `path` and the file itself (truncating). With `swmr`, the file
// uses the 1.10 format and single-writer/multiple-reader mode, which keeps everything flushed
// readable after a SIGKILL (see H5Output); *got_swmr says whether that mode could be had.
// Throws sim::InputError naming the path when the file cannot be created.
Handle CreateFile(const std::string& path, bool swmr, bool* got_swmr);

// Root or object attributes; an existing attribute of that name is replaced. Strings are stored
// as variable-length UTF-8.
void WriteStringAttribute(hid_t object, const std::string& name, const std::string& value);
void WriteDoubleAttribute(hid_t object, const std::string& name, double value);
void WriteU64Attribute(hid_t object, const std::string& name, uint64_t value);
// `state_hash` as 16 lower-case hex digits and `state_hash_u64` as an unsigned 64-bit integer.
void WriteStateHash(hid_t object, uint64_t hash);
std::string HexHash(uint64_t hash);
// Reads a string attribute (variable- or fixed-length); throws std::runtime_error if absent.
std::string ReadStringAttribute(hid_t object, const std::string& name);

// Writes a fixed-size array dataset `name` under `location`: (rows x width), 1-D when width == 1.
// Chunked (up to kSnapshotChunkRows rows) with shuffle + deflate level 4 when rows > 0
// (contiguous when empty: HDF5 chunks must not be empty). `file_type` is the stored type,
// `memory_type` that of `data`.
constexpr hsize_t kSnapshotChunkRows = 16384;
void WriteArray(hid_t location, const std::string& name, hid_t file_type, hid_t memory_type,
                const void* data, hsize_t rows, hsize_t width);

// Storage indices of the particles sorted by persistent id (output is always in id order).
std::vector<size_t> IdOrder(const dem::Particles& particles);

// One particle snapshot as referenced by the XDMF sidecar.
struct SnapshotEntry {
  std::string group;  // "/snapshots/000012"
  double time = 0;    // [s]
  int64_t count = 0;  // particles
};
std::string SnapshotGroupName(int64_t index);

// Writes group /snapshots/NNNNNN (attribute time; datasets id int64 (N), position, velocity,
// angular_velocity (N x 3) [SI], radius (N), material int32 (N), speed |v| (N), connectivity
// int64 0..N-1 (N), all in persistent-id order. This is the one writer of particle arrays: the
// bed file hard-links its /particles datasets to the snapshot's.
SnapshotEntry WriteParticleSnapshot(hid_t file, int64_t index, double time,
                                    const dem::Particles& particles);

// "<path without extension>.xdmf" next to the HDF5 file.
std::string XdmfPath(const std::string& h5_path);
// (Re)writes the XDMF3 sidecar of `h5_path` listing `snapshots` as a temporal collection of
// Polyvertex grids (ParaView 5.11 needs the explicit connectivity item). Written to a temporary
// file and renamed, so a reader never sees half a file. Throws std::runtime_error on I/O failure.
void WriteXdmf(const std::string& h5_path, const std::vector<SnapshotEntry>& snapshots);

}  // namespace sim::h5
