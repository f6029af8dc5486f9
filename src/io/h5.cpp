#include "h5.h"

#include <algorithm>
#include <cstring>

namespace magbake::io::h5 {
namespace {

// The innermost (most specific) message on the current error stack.
herr_t walk(unsigned n, const H5E_error2_t* e, void* out) {
  auto* s = static_cast<std::string*>(out);
  if (n == 0 || s->empty()) *s = e->desc ? e->desc : "";
  char minor[256] = "";
  H5Eget_msg(e->min_num, nullptr, minor, sizeof minor);
  if (n == 0 && minor[0]) *s += std::string(" (") + minor + ")";
  return 0;
}

std::string stack_message() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk, &msg);
  // The file driver's report is long ("file write failed: time = ..., error message = '...'"):
  // keep the system's message.
  const std::string key = "error message = '";
  if (const auto at = msg.find(key); at != std::string::npos) {
    const auto end = msg.find('\'', at + key.size());
    msg = msg.substr(at + key.size(), end == std::string::npos ? std::string::npos : end - at - key.size());
    errno = 0;
  }
  // System errors (disk full) are reported by errno through the driver.
  if (errno != 0 && msg.find("errno") == std::string::npos) {
    msg += std::string("; ") + std::strerror(errno);
  }
  return msg;
}

}  // namespace

void check(herr_t status, const std::string& what) {
  if (status < 0) throw Error(what + ": " + stack_message());
}

hid_t check_id(hid_t id, const std::string& what) {
  if (id < 0) throw Error(what + ": " + stack_message());
  return id;
}

void quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

void no_atexit() {
  // HDF5 closes open files at exit; a file whose writes failed (disk full) then crashes the
  // library in 1.10. The process frees everything anyway.
  H5dont_atexit();
}

void Handle::reset() {
  if (id_ < 0) return;
  switch (H5Iget_type(id_)) {
    case H5I_FILE: H5Fclose(id_); break;
    case H5I_GROUP: H5Gclose(id_); break;
    case H5I_DATASET: H5Dclose(id_); break;
    case H5I_DATASPACE: H5Sclose(id_); break;
    case H5I_DATATYPE: H5Tclose(id_); break;
    case H5I_ATTR: H5Aclose(id_); break;
    case H5I_GENPROP_LST: H5Pclose(id_); break;
    default: break;
  }
  id_ = -1;
}

Handle create_group(hid_t parent, const std::string& name) {
  return Handle(check_id(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "create group " + name));
}

void attr_string(hid_t obj, const std::string& name, const std::string& value) {
  Handle type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.id(), value.empty() ? 1 : value.size());
  H5Tset_strpad(type.id(), H5T_STR_NULLTERM);
  Handle space(H5Screate(H5S_SCALAR));
  Handle a(check_id(H5Acreate2(obj, name.c_str(), type.id(), space.id(), H5P_DEFAULT, H5P_DEFAULT), "attribute " + name));
  check(H5Awrite(a.id(), type.id(), value.empty() ? "" : value.data()), "write attribute " + name);
}

void attr_double(hid_t obj, const std::string& name, const std::vector<double>& v) {
  const hsize_t n = v.size();
  Handle space(n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr));
  Handle a(check_id(H5Acreate2(obj, name.c_str(), H5T_IEEE_F64LE, space.id(), H5P_DEFAULT, H5P_DEFAULT), "attribute " + name));
  check(H5Awrite(a.id(), H5T_NATIVE_DOUBLE, v.data()), "write attribute " + name);
}

void attr_int(hid_t obj, const std::string& name, const std::vector<std::int64_t>& v) {
  const hsize_t n = v.size();
  Handle space(n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr));
  Handle a(check_id(H5Acreate2(obj, name.c_str(), H5T_STD_I64LE, space.id(), H5P_DEFAULT, H5P_DEFAULT), "attribute " + name));
  check(H5Awrite(a.id(), H5T_NATIVE_INT64, v.data()), "write attribute " + name);
}

namespace {
// Fixed arrays of at least this many elements are chunked and compressed (write_any).
constexpr hsize_t kCompressFrom = 1 << 16;
// Elements per chunk of those arrays (1 MB of float64).
constexpr hsize_t kChunkElements = 1 << 17;

void write_any(hid_t parent, const std::string& name, const std::vector<hsize_t>& shape, hid_t file_type,
               hid_t mem_type, const void* data, const std::string& unit) {
  Handle space(H5Screate_simple(int(shape.size()), shape.data(), nullptr));
  hsize_t total = 1;
  for (hsize_t s : shape) total *= s;
  // Large arrays (a shot's tessellated geometry: 1000 spheres are 80 MB raw, mostly repeats of
  // one mesh) are stored in chunks of about 1 MB with shuffle + deflate, which every HDF5 reader
  // undoes transparently; small ones stay contiguous.
  Handle plist(H5Pcreate(H5P_DATASET_CREATE));
  if (total >= kCompressFrom && !shape.empty()) {
    std::vector<hsize_t> chunk = shape;
    const hsize_t row = total / shape[0];
    chunk[0] = std::clamp<hsize_t>(kChunkElements / std::max<hsize_t>(row, 1), 1, shape[0]);
    check(H5Pset_chunk(plist.id(), int(chunk.size()), chunk.data()), "chunk " + name);
    check(H5Pset_shuffle(plist.id()), "shuffle " + name);
    check(H5Pset_deflate(plist.id(), 1), "deflate " + name);
  }
  Handle d(check_id(H5Dcreate2(parent, name.c_str(), file_type, space.id(), H5P_DEFAULT, plist.id(), H5P_DEFAULT),
                    "create dataset " + name));
  if (total > 0) check(H5Dwrite(d.id(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
  if (!unit.empty()) attr_string(d.id(), "unit", unit);
}
}  // namespace

void write_doubles(hid_t parent, const std::string& name, const std::vector<hsize_t>& shape, const double* data,
                   const std::string& unit) {
  write_any(parent, name, shape, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, data, unit);
}

void write_ints(hid_t parent, const std::string& name, const std::vector<hsize_t>& shape, const std::int64_t* data) {
  write_any(parent, name, shape, H5T_STD_I64LE, H5T_NATIVE_INT64, data, "");
}

void write_strings(hid_t parent, const std::string& name, const std::vector<std::string>& values) {
  // Fixed-length strings (the longest), readable as bytes by h5py and every HDF5 tool.
  std::size_t len = 1;
  for (const auto& v : values) len = std::max(len, v.size());
  std::vector<char> buf(values.size() * len, 0);
  for (std::size_t i = 0; i < values.size(); ++i) std::memcpy(buf.data() + i * len, values[i].data(), values[i].size());
  Handle type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type.id(), len);
  H5Tset_strpad(type.id(), H5T_STR_NULLPAD);
  const hsize_t n = values.size();
  Handle space(H5Screate_simple(1, &n, nullptr));
  Handle d(check_id(H5Dcreate2(parent, name.c_str(), type.id(), space.id(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                    "create dataset " + name));
  if (n) check(H5Dwrite(d.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), "write " + name);
}

Handle create_series(hid_t parent, const std::string& name, hid_t type, const std::vector<hsize_t>& tail,
                     hsize_t chunk_frames, const std::string& unit) {
  std::vector<hsize_t> dims{0}, max{H5S_UNLIMITED}, chunk{chunk_frames};
  for (hsize_t t : tail) dims.push_back(t), max.push_back(t), chunk.push_back(std::max<hsize_t>(t, 1));
  Handle space(H5Screate_simple(int(dims.size()), dims.data(), max.data()));
  Handle plist(H5Pcreate(H5P_DATASET_CREATE));
  check(H5Pset_chunk(plist.id(), int(chunk.size()), chunk.data()), "chunk " + name);
  check(H5Pset_shuffle(plist.id()), "shuffle " + name);
  check(H5Pset_deflate(plist.id(), 4), "deflate " + name);
  const hid_t file_type = H5Tequal(type, H5T_NATIVE_DOUBLE) > 0 ? H5T_IEEE_F64LE : H5T_STD_I64LE;
  Handle d(check_id(H5Dcreate2(parent, name.c_str(), file_type, space.id(), H5P_DEFAULT, plist.id(), H5P_DEFAULT),
                    "create dataset " + name));
  if (!unit.empty()) attr_string(d.id(), "unit", unit);
  return d;
}

void write_row(hid_t dataset, hid_t type, hsize_t index, const void* row) { write_rows(dataset, type, index, 1, row); }

void write_rows(hid_t dataset, hid_t type, hsize_t first, hsize_t rows, const void* data) {
  if (rows == 0) return;
  Handle fs(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(fs.id());
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(fs.id(), dims.data(), nullptr);
  if (dims[0] < first + rows) {
    dims[0] = first + rows;
    check(H5Dset_extent(dataset, dims.data()), "extend dataset");
  }
  Handle file_space(H5Dget_space(dataset));
  std::vector<hsize_t> start(rank, 0), count = dims;
  start[0] = first;
  count[0] = rows;
  check(H5Sselect_hyperslab(file_space.id(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), "select rows");
  Handle mem(H5Screate_simple(rank, count.data(), nullptr));
  check(H5Dwrite(dataset, type, mem.id(), file_space.id(), H5P_DEFAULT, data), "write rows");
}

bool exists(hid_t parent, const std::string& path) {
  // Walk the path one link at a time (H5Lexists fails on missing intermediate groups).
  std::string sofar;
  std::size_t pos = 0;
  while (pos <= path.size()) {
    const std::size_t next = path.find('/', pos);
    sofar = path.substr(0, next);
    if (!sofar.empty() && H5Lexists(parent, sofar.c_str(), H5P_DEFAULT) <= 0) return false;
    if (next == std::string::npos) break;
    pos = next + 1;
  }
  return true;
}

std::vector<hsize_t> shape(hid_t dataset) {
  Handle s(H5Dget_space(dataset));
  const int rank = H5Sget_simple_extent_ndims(s.id());
  std::vector<hsize_t> dims(std::max(rank, 0));
  if (rank > 0) H5Sget_simple_extent_dims(s.id(), dims.data(), nullptr);
  return dims;
}

namespace {
// Elements in a dataset of `dims`; throws for more than a reader will ever hold (a corrupt or
// hostile file declaring a huge extent must not exhaust memory).
hsize_t element_count(const std::vector<hsize_t>& dims, std::size_t element_size, const std::string& path) {
  constexpr hsize_t kMaxBytes = hsize_t(1) << 33;  // 8 GiB
  hsize_t total = 1;
  for (hsize_t s : dims) {
    if (s != 0 && total > kMaxBytes / element_size / s) throw Error(path + ": dataset too large to read");
    total *= s;
  }
  return total;
}

template <class T>
std::vector<T> read_all(hid_t parent, const std::string& path, hid_t mem_type) {
  Handle d(check_id(H5Dopen2(parent, path.c_str(), H5P_DEFAULT), "open " + path));
  const hsize_t total = element_count(shape(d.id()), sizeof(T), path);
  std::vector<T> out(total);
  if (total) check(H5Dread(d.id(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), "read " + path);
  return out;
}
}  // namespace

std::vector<double> read_doubles(hid_t parent, const std::string& path) {
  return read_all<double>(parent, path, H5T_NATIVE_DOUBLE);
}
std::vector<std::int64_t> read_ints(hid_t parent, const std::string& path) {
  return read_all<std::int64_t>(parent, path, H5T_NATIVE_INT64);
}

std::vector<std::string> read_strings(hid_t parent, const std::string& path) {
  Handle d(check_id(H5Dopen2(parent, path.c_str(), H5P_DEFAULT), "open " + path));
  Handle type(H5Dget_type(d.id()));
  if (H5Tget_class(type.id()) != H5T_STRING || H5Tis_variable_str(type.id()) > 0) throw Error(path + ": not fixed strings");
  const std::size_t len = H5Tget_size(type.id());
  if (len == 0) throw Error(path + ": zero-length strings");
  const hsize_t n = element_count(shape(d.id()), len, path);  // every element (any rank)
  std::vector<char> buf(n * len);
  if (n) check(H5Dread(d.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), "read " + path);
  std::vector<std::string> out;
  for (hsize_t i = 0; i < n; ++i) out.emplace_back(buf.data() + i * len, strnlen(buf.data() + i * len, len));
  return out;
}

std::vector<double> read_rows(hid_t parent, const std::string& path, hsize_t first, hsize_t count) {
  Handle d(check_id(H5Dopen2(parent, path.c_str(), H5P_DEFAULT), "open " + path));
  std::vector<hsize_t> dims = shape(d.id());
  if (dims.empty() || first > dims[0] || count > dims[0] - first) throw Error(path + ": rows out of range");
  std::vector<hsize_t> start(dims.size(), 0), cnt = dims;
  start[0] = first;
  cnt[0] = count;
  const hsize_t total = element_count(cnt, sizeof(double), path);
  std::vector<double> out(total);
  if (!total) return out;
  Handle fs(H5Dget_space(d.id()));
  check(H5Sselect_hyperslab(fs.id(), H5S_SELECT_SET, start.data(), nullptr, cnt.data(), nullptr), "select " + path);
  Handle ms(H5Screate_simple(int(cnt.size()), cnt.data(), nullptr));
  check(H5Dread(d.id(), H5T_NATIVE_DOUBLE, ms.id(), fs.id(), H5P_DEFAULT, out.data()), "read " + path);
  return out;
}

std::string read_attr_string(hid_t obj, const std::string& name) {
  Handle a(check_id(H5Aopen(obj, name.c_str(), H5P_DEFAULT), "attribute " + name));
  Handle type(H5Aget_type(a.id()));
  if (H5Tget_class(type.id()) != H5T_STRING) throw Error("attribute " + name + " is not a string");
  {
    Handle space(H5Aget_space(a.id()));
    if (H5Sget_simple_extent_npoints(space.id()) != 1) throw Error("attribute " + name + " is not a single string");
  }
  if (H5Tis_variable_str(type.id()) > 0) {
    char* s = nullptr;
    Handle mt(H5Tcopy(H5T_C_S1));
    H5Tset_size(mt.id(), H5T_VARIABLE);
    check(H5Aread(a.id(), mt.id(), &s), "read attribute " + name);
    std::string out = s ? s : "";
    H5free_memory(s);
    return out;
  }
  const std::size_t len = H5Tget_size(type.id());
  std::vector<char> buf(len + 1, 0);
  check(H5Aread(a.id(), type.id(), buf.data()), "read attribute " + name);
  return std::string(buf.data(), strnlen(buf.data(), len));
}

std::vector<double> read_attr_doubles(hid_t obj, const std::string& name) {
  Handle a(check_id(H5Aopen(obj, name.c_str(), H5P_DEFAULT), "attribute " + name));
  Handle s(H5Aget_space(a.id()));
  const hssize_t n = H5Sget_simple_extent_npoints(s.id());
  if (n > (hssize_t(1) << 24)) throw Error("attribute " + name + " is too large");
  std::vector<double> out(std::max<hssize_t>(n, 0));
  check(H5Aread(a.id(), H5T_NATIVE_DOUBLE, out.data()), "read attribute " + name);
  return out;
}

std::string library_version() {
  unsigned maj, min, rel;
  H5get_libversion(&maj, &min, &rel);
  return std::to_string(maj) + "." + std::to_string(min) + "." + std::to_string(rel);
}

}  // namespace magbake::io::h5
