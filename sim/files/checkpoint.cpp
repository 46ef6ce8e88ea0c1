#include "sim/files/checkpoint.h"

#include <hdf5.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "dem/archive.h"
#include "sim/files/internal_h5.h"
#include "sim/input/scene.h"

namespace sim {
namespace {

using h5::CheckId;
using h5::CheckOk;
using h5::Handle;

}  // namespace

std::string CheckpointPath(const std::string& output) {
  return std::filesystem::path(output).replace_extension(".restart.h5").string();
}

void WriteCheckpoint(const std::string& path, const Checkpoint& c) {
  namespace fs = std::filesystem;
  const std::string temporary = path + "." + std::to_string(::getpid()) + ".partial";
  try {
    Handle file = h5::CreateFile(temporary, /*swmr=*/false, nullptr, path);
    h5::WriteNewFile(file.get(), path, [&] {
      Handle root(CheckId(H5Gopen2(file.get(), "/", H5P_DEFAULT), "H5Gopen2 /"), H5Gclose);
      h5::WriteStringAttribute(root.get(), "format", "scoopsim restart");
      h5::WriteDoubleAttribute(root.get(), "format_version", kCheckpointFormat);
      h5::WriteStringAttribute(root.get(), "version", SCOOPSIM_VERSION);
      h5::WriteStringAttribute(root.get(), "scene_path", c.scene_path);
      h5::WriteStringAttribute(root.get(), "scene_yaml", c.scene_yaml);
      h5::WriteDoubleAttribute(root.get(), "time", c.time);
      h5::WriteBytes(file.get(), "dem_state", c.dem_state);
      h5::WriteBytes(file.get(), "world_state", c.world_state);
      h5::WriteBytes(file.get(), "output_state", c.output_state);
    });
    CheckOk(file.reset(), "H5Fclose " + temporary);
    fs::rename(temporary, path);
  } catch (const OutputError&) {  // a full disk: "PATH: write failed (REASON)"
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw InputError(path + ": cannot write the checkpoint: " + e.what());
  }
}

Checkpoint ReadCheckpoint(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path + ": no checkpoint (run with --checkpoint-every S to keep one)");
  const Handle file = h5::OpenForReading(path, false);
  const h5::Reader in(path, file.get());
  if (!in.HasAttribute("/", "format") ||
      in.ReadStringAttribute("/", "format") != "scoopsim restart")
    in.Fail("attribute format", "expected \"scoopsim restart\": not a checkpoint");
  const double version = in.ReadDoubleAttribute("/", "format_version");
  if (version != kCheckpointFormat) {
    char got[32];
    std::snprintf(got, sizeof got, "%g", version);
    in.Fail("attribute format_version", "expected " + std::to_string(kCheckpointFormat) + ", got " +
                                            got + " (written by scoopsim " +
                                            in.ReadStringAttribute("/", "version") + ")");
  }
  Checkpoint c;
  c.scene_path = in.ReadStringAttribute("/", "scene_path");
  c.scene_yaml = in.ReadStringAttribute("/", "scene_yaml");
  c.time = in.ReadDoubleAttribute("/", "time");
  c.dem_state = in.ReadBytes("/dem_state");
  c.world_state = in.ReadBytes("/world_state");
  c.output_state = in.ReadBytes("/output_state");
  return c;
}

std::vector<char> EncodeCursor(const OutputCursor& cursor) {
  dem::ArchiveWriter a;
  a(static_cast<uint64_t>(cursor.rows.size()));
  for (const auto& [name, rows] : cursor.rows) {
    a(name);
    a(rows);
  }
  a(cursor.snapshot_time);
  a(cursor.snapshot_count);
  return a.bytes();
}

OutputCursor DecodeCursor(const std::vector<char>& bytes, const std::string& path) {
  OutputCursor cursor;
  try {
    dem::ArchiveReader a(bytes);
    uint64_t n = 0;
    a(n);
    for (uint64_t k = 0; k < n; ++k) {
      std::string name;
      int64_t rows = 0;
      a(name);
      a(rows);
      cursor.rows.emplace_back(name, rows);
    }
    a(cursor.snapshot_time);
    a(cursor.snapshot_count);
    if (!a.done() || cursor.snapshot_time.size() != cursor.snapshot_count.size())
      throw std::runtime_error("bytes left over");
  } catch (const std::runtime_error& e) {
    throw InputError(path + ": /output_state: " + e.what());
  }
  return cursor;
}

}  // namespace sim
