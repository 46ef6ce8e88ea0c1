// The reading half of sim/files/internal_h5.h: opening a file read-only and h5::Reader, shared by
// the bed files (bed_io.cpp) and the reader of saved runs (saved_run.cpp).
#include <hdf5.h>

#include <algorithm>
#include <string>
#include <vector>

#include "sim/files/internal_h5.h"
#include "sim/input/scene.h"

namespace sim::h5 {
namespace {

// "attribute time" for the root group, "/snapshots/000001 attribute time" otherwise.
std::string AttributeLabel(const std::string& object, const std::string& attribute) {
  return (object == "/" ? std::string() : object + " ") + "attribute " + attribute;
}

}  // namespace

Handle OpenForReading(const std::string& path, bool swmr_fallback) {
  hid_t file = H5I_INVALID_HID;
  H5E_BEGIN_TRY {
    file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0 && swmr_fallback) {
      file = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT);
    }
  }
  H5E_END_TRY;
  if (file < 0) throw InputError(path + ": not a readable HDF5 file");
  return Handle(file, H5Fclose);
}

void Reader::Fail(const std::string& object, const std::string& message) const {
  throw InputError(path_ + ": " + object + ": " + message);
}

bool Reader::Exists(const std::string& name) const {
  // One link at a time: H5Lexists fails on a missing intermediate group.
  if (name == "/") return true;
  for (size_t slash = name.find('/', 1);; slash = name.find('/', slash + 1)) {
    const std::string prefix = name.substr(0, slash);
    htri_t exists = -1;
    H5E_BEGIN_TRY { exists = H5Lexists(file_, prefix.c_str(), H5P_DEFAULT); }
    H5E_END_TRY;
    if (exists <= 0) return false;
    if (slash == std::string::npos) return true;
  }
}

std::vector<std::string> Reader::List(const std::string& name) const {
  if (!Exists(name)) Fail(name, "missing");
  hid_t group_id = H5I_INVALID_HID;
  H5E_BEGIN_TRY { group_id = H5Gopen2(file_, name.c_str(), H5P_DEFAULT); }
  H5E_END_TRY;
  if (group_id < 0) Fail(name, "not a group");
  const Handle group(group_id, H5Gclose);
  H5G_info_t info{};
  if (H5Gget_info(group.get(), &info) < 0) Fail(name, "cannot be read (damaged file?)");
  std::vector<std::string> names;
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    const ssize_t size = H5Lget_name_by_idx(group.get(), ".", H5_INDEX_NAME, H5_ITER_INC, k,
                                            nullptr, 0, H5P_DEFAULT);
    if (size < 0) Fail(name, "cannot be read (damaged file?)");
    std::string link(static_cast<size_t>(size) + 1, '\0');
    H5Lget_name_by_idx(group.get(), ".", H5_INDEX_NAME, H5_ITER_INC, k, link.data(), link.size(),
                       H5P_DEFAULT);
    link.resize(static_cast<size_t>(size));
    names.push_back(std::move(link));
  }
  std::sort(names.begin(), names.end());
  return names;
}

Handle Reader::OpenDataset(const std::string& name) const {
  if (!Exists(name)) Fail(name, "missing");
  hid_t dataset = H5I_INVALID_HID;
  H5E_BEGIN_TRY { dataset = H5Dopen2(file_, name.c_str(), H5P_DEFAULT); }
  H5E_END_TRY;
  if (dataset < 0) Fail(name, "not a dataset");
  return Handle(dataset, H5Dclose);
}

hsize_t Reader::CheckShape(const std::string& name, hid_t dataset, H5T_class_t type_class,
                           int64_t rows, hsize_t width, bool at_least) const {
  const Handle space(CheckId(H5Dget_space(dataset), "H5Dget_space " + name), H5Sclose);
  const int expected_rank = width == 1 ? 1 : 2;
  hsize_t dims[H5S_MAX_RANK] = {};
  const int rank = H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  const std::string want = rows < 0 ? "n" : (at_least ? ">= " : "") + std::to_string(rows);
  const std::string expected =
      "(" + want + (width == 1 ? std::string() : ", " + std::to_string(width)) + ")";
  const bool rows_ok = rows < 0 || dims[0] == static_cast<hsize_t>(rows) ||
                       (at_least && dims[0] > static_cast<hsize_t>(rows));
  if (rank != expected_rank || (width > 1 && dims[1] != width) || !rows_ok) {
    std::string got = "(";
    for (int i = 0; i < rank; ++i) got += (i ? ", " : "") + std::to_string(dims[i]);
    Fail(name, "expected shape " + expected + ", got " + got + ")");
  }
  const Handle type(CheckId(H5Dget_type(dataset), "H5Dget_type " + name), H5Tclose);
  const H5T_class_t stored = H5Tget_class(type.get());
  if (type_class == H5T_NO_CLASS ? (stored != H5T_FLOAT && stored != H5T_INTEGER)
                                 : stored != type_class) {
    Fail(name, type_class == H5T_FLOAT     ? "expected floating-point numbers"
               : type_class == H5T_INTEGER ? "expected integers"
                                           : "expected numbers");
  }
  return dims[0];
}

void Reader::ReadAll(const std::string& name, hid_t dataset, hid_t memory_type, void* data) const {
  herr_t status = -1;
  H5E_BEGIN_TRY { status = H5Dread(dataset, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data); }
  H5E_END_TRY;
  if (status < 0) Fail(name, "cannot be read (damaged file?)");
}

void Reader::ReadFirstRows(const std::string& name, hid_t dataset, hid_t memory_type, int64_t rows,
                           hsize_t width, void* data) const {
  const int rank = width == 1 ? 1 : 2;
  const hsize_t count[2] = {static_cast<hsize_t>(rows), width};
  const hsize_t start[2] = {0, 0};
  const Handle file_space(CheckId(H5Dget_space(dataset), "H5Dget_space " + name), H5Sclose);
  CheckOk(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr),
          "H5Sselect_hyperslab " + name);
  const Handle memory_space(CheckId(H5Screate_simple(rank, count, nullptr), "H5Screate " + name),
                            H5Sclose);
  herr_t status = -1;
  H5E_BEGIN_TRY {
    status = H5Dread(dataset, memory_type, memory_space.get(), file_space.get(), H5P_DEFAULT, data);
  }
  H5E_END_TRY;
  if (status < 0) Fail(name, "cannot be read (damaged file?)");
}

std::vector<dem::Vec3> Reader::ReadVectors(const std::string& name, int64_t rows,
                                           bool series) const {
  int64_t n = rows;
  const std::vector<double> flat =
      series && rows >= 0 ? ReadSeries<double>(name, H5T_FLOAT, H5T_NATIVE_DOUBLE, rows, 3)
                          : Read<double>(name, H5T_FLOAT, H5T_NATIVE_DOUBLE, rows, 3, &n);
  std::vector<dem::Vec3> out(static_cast<size_t>(n));
  for (size_t k = 0; k < out.size(); ++k) out[k] = {flat[3 * k], flat[3 * k + 1], flat[3 * k + 2]};
  return out;
}

std::vector<char> Reader::ReadBytes(const std::string& name) const {
  const std::vector<uint8_t> b = Read<uint8_t>(name, H5T_INTEGER, H5T_NATIVE_UINT8, -1, 1);
  return std::vector<char>(b.begin(), b.end());
}

std::vector<std::string> Reader::ReadStrings(const std::string& name) const {
  const Handle dataset = OpenDataset(name);
  const Handle space(CheckId(H5Dget_space(dataset.get()), "H5Dget_space " + name), H5Sclose);
  hsize_t dims[H5S_MAX_RANK] = {};
  if (H5Sget_simple_extent_dims(space.get(), dims, nullptr) != 1) {
    Fail(name, "expected a 1-D list of strings");
  }
  const Handle type(CheckId(H5Dget_type(dataset.get()), "H5Dget_type " + name), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING) Fail(name, "expected strings");
  const size_t n = dims[0];
  std::vector<std::string> out;
  if (n == 0) return out;
  // Read with a copy of the file's own type: a converted character set would make HDF5 refuse.
  const Handle memory_type(CheckId(H5Tcopy(type.get()), "H5Tcopy"), H5Tclose);
  if (H5Tis_variable_str(type.get()) > 0) {
    std::vector<char*> pointers(n, nullptr);
    ReadAll(name, dataset.get(), memory_type.get(), pointers.data());
    for (char* s : pointers) out.emplace_back(s != nullptr ? s : "");
    H5Dvlen_reclaim(memory_type.get(), space.get(), H5P_DEFAULT, pointers.data());
  } else {
    const size_t size = H5Tget_size(type.get());
    std::vector<char> buffer(n * size);
    ReadAll(name, dataset.get(), memory_type.get(), buffer.data());
    for (size_t k = 0; k < n; ++k) {
      const std::string s(buffer.data() + k * size, size);
      out.push_back(s.substr(0, s.find('\0')));
    }
  }
  return out;
}

bool Reader::HasAttribute(const std::string& object, const std::string& attribute) const {
  if (!Exists(object)) return false;
  htri_t exists = -1;
  H5E_BEGIN_TRY {
    exists = H5Aexists_by_name(file_, object.c_str(), attribute.c_str(), H5P_DEFAULT);
  }
  H5E_END_TRY;
  return exists > 0;
}

Handle Reader::OpenAttribute(const std::string& object, const std::string& attribute) const {
  const std::string label = AttributeLabel(object, attribute);
  if (!HasAttribute(object, attribute)) Fail(label, "missing");
  hid_t id = H5I_INVALID_HID;
  H5E_BEGIN_TRY {
    id = H5Aopen_by_name(file_, object.c_str(), attribute.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  }
  H5E_END_TRY;
  if (id < 0) Fail(label, "cannot be read (damaged file?)");
  return Handle(id, H5Aclose);
}

double Reader::ReadDoubleAttribute(const std::string& object, const std::string& attribute) const {
  const std::string label = AttributeLabel(object, attribute);
  const Handle attr = OpenAttribute(object, attribute);
  const Handle type(CheckId(H5Aget_type(attr.get()), "H5Aget_type " + label), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_FLOAT) Fail(label, "expected a number");
  double value = 0;
  herr_t status = -1;
  H5E_BEGIN_TRY { status = H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &value); }
  H5E_END_TRY;
  if (status < 0) Fail(label, "cannot be read (damaged file?)");
  return value;
}

std::string Reader::ReadStringAttribute(const std::string& object,
                                        const std::string& attribute) const {
  const std::string label = AttributeLabel(object, attribute);
  if (!HasAttribute(object, attribute)) Fail(label, "missing");
  hid_t id = H5I_INVALID_HID;
  H5E_BEGIN_TRY { id = H5Oopen(file_, object.c_str(), H5P_DEFAULT); }
  H5E_END_TRY;
  if (id < 0) Fail(object, "cannot be opened (damaged file?)");
  const Handle owner(id, H5Oclose);
  try {
    return h5::ReadStringAttribute(owner.get(), attribute);
  } catch (const std::runtime_error&) {
    Fail(label, "expected a string");
  }
}

}  // namespace sim::h5
