// A thin RAII layer over the HDF5 C API (Debian's libhdf5 1.10): handles, typed helpers and
// errors as exceptions with HDF5's own message. Only what the cache needs.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace magbake::io::h5 {

/// An HDF5 failure, with the library's innermost message (e.g. "No space left on device").
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws Error(what + HDF5's message) when status < 0.
void check(herr_t status, const std::string& what);
hid_t check_id(hid_t id, const std::string& what);
/// Silences HDF5's automatic error printing (call once; messages come through Error).
void quiet();
/// Keeps HDF5 from closing files at process exit (call first thing in main).
void no_atexit();

/// An owned hid_t closed with the right H5*close.
class Handle {
 public:
  Handle() = default;
  explicit Handle(hid_t id) : id_(id) {}
  ~Handle() { reset(); }
  Handle(Handle&& o) noexcept : id_(o.id_) { o.id_ = -1; }
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) reset(), id_ = o.id_, o.id_ = -1;
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t id() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  void reset();
  /// Gives up ownership without closing (after the id was closed by hand); returns it.
  hid_t release() {
    const hid_t id = id_;
    id_ = -1;
    return id;
  }

 private:
  hid_t id_ = -1;
};

// ---- writing
Handle create_group(hid_t parent, const std::string& name);
void attr_string(hid_t obj, const std::string& name, const std::string& value);
void attr_double(hid_t obj, const std::string& name, const std::vector<double>& values);
void attr_int(hid_t obj, const std::string& name, const std::vector<std::int64_t>& values);
/// A fixed-size float64 dataset of the given shape (chunked, shuffled and deflated from 65,536
/// elements on; readers see no difference).
void write_doubles(hid_t parent, const std::string& name, const std::vector<hsize_t>& shape, const double* data,
                   const std::string& unit = "");
void write_ints(hid_t parent, const std::string& name, const std::vector<hsize_t>& shape, const std::int64_t* data);
void write_strings(hid_t parent, const std::string& name, const std::vector<std::string>& values);
/// An extendable frame-major dataset: shape [0, tail...], unlimited first axis, chunked by
/// `chunk_frames` frames, shuffle + deflate. type: H5T_NATIVE_DOUBLE or H5T_NATIVE_INT64.
Handle create_series(hid_t parent, const std::string& name, hid_t type, const std::vector<hsize_t>& tail,
                     hsize_t chunk_frames, const std::string& unit = "");
/// Writes row `index` of a series (extending it to index + 1 rows).
void write_row(hid_t dataset, hid_t type, hsize_t index, const void* row);
/// Writes rows [first, first + rows) of a series from `data` (rows x the row size), extending it.
void write_rows(hid_t dataset, hid_t type, hsize_t first, hsize_t rows, const void* data);

// ---- reading
bool exists(hid_t parent, const std::string& path);
std::vector<hsize_t> shape(hid_t dataset);
std::vector<double> read_doubles(hid_t parent, const std::string& path);
std::vector<std::int64_t> read_ints(hid_t parent, const std::string& path);
std::vector<std::string> read_strings(hid_t parent, const std::string& path);
/// Rows [first, first + count) of a frame-major dataset, as doubles.
std::vector<double> read_rows(hid_t parent, const std::string& path, hsize_t first, hsize_t count);
std::string read_attr_string(hid_t obj, const std::string& name);
std::vector<double> read_attr_doubles(hid_t obj, const std::string& name);

/// Library version, e.g. "1.10.8".
std::string library_version();

}  // namespace magbake::io::h5
