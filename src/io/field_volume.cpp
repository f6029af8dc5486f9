#include "field_volume.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>

#include <cmath>
#include <sstream>
#include <filesystem>
#include <mutex>
#include <ostream>
#include <streambuf>
#include <stdexcept>

namespace magbake::io {
namespace {

// A stream buffer that only counts the bytes written to it.
class ByteCounter : public std::streambuf {
 public:
  std::streamsize bytes() const { return bytes_; }

 protected:
  int_type overflow(int_type c) override {
    if (!traits_type::eq_int_type(c, traits_type::eof())) ++bytes_;
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char*, std::streamsize n) override {
    bytes_ += n;
    return n;
  }

 private:
  std::streamsize bytes_ = 0;
};

}  // namespace

float display_density(float b, double low, double high) {
  if (!(b > low)) return 0.0f;
  if (!(high > low) || b >= high) return 1.0f;
  return static_cast<float>(std::log(b / low) / std::log(high / low));
}

double density_floor(const VolumeInfo& info) { return info.threshold > 0 ? info.threshold : kAutoThresholdFraction * info.reference; }

std::size_t write_field_volume(const std::string& path, const FieldSamples& s, const VolumeInfo& info) {
  static std::once_flag init;
  std::call_once(init, [] { openvdb::initialize(); });
  // Index space: voxel (i, j, k) of the samples is index coordinate (i0 + i, ...) with the
  // transform's origin at the world origin, so volumes of different frames line up.
  const openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(s.voxel);
  const Eigen::Vector3i i0(static_cast<int>(std::lround(s.origin[0] / s.voxel)),
                           static_cast<int>(std::lround(s.origin[1] / s.voxel)),
                           static_cast<int>(std::lround(s.origin[2] / s.voxel)));
  const openvdb::Vec3s applied(float(s.applied[0]), float(s.applied[1]), float(s.applied[2]));
  auto B = openvdb::Vec3SGrid::create(applied);
  auto density = openvdb::FloatGrid::create(0.0f);
  B->setTransform(xform);
  density->setTransform(xform->copy());
  B->setName("B");
  density->setName("density");
  B->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
  B->setGridClass(openvdb::GRID_UNKNOWN);
  density->setGridClass(openvdb::GRID_UNKNOWN);
  std::size_t active = 0;
  const double low = density_floor(info);
  {
    auto ba = B->getAccessor();
    auto da = density->getAccessor();
    for (int k = 0; k < s.dims[2]; ++k) {
      for (int j = 0; j < s.dims[1]; ++j) {
        for (int i = 0; i < s.dims[0]; ++i) {
          const std::size_t q = s.index(i, j, k);
          const float x = s.bx[q], y = s.by[q], z = s.bz[q];
          if (std::isnan(x)) continue;
          const float mag = std::sqrt(x * x + y * y + z * z);
          if (!(mag >= info.threshold)) continue;
          const openvdb::Coord c(i0[0] + i, i0[1] + j, i0[2] + k);
          ba.setValue(c, openvdb::Vec3s(x, y, z) + applied);
          da.setValue(c, display_density(mag, low, info.reference));
          ++active;
        }
      }
    }
  }
  openvdb::tools::prune(B->tree());
  openvdb::tools::prune(density->tree());
  for (openvdb::GridBase* g : {static_cast<openvdb::GridBase*>(B.get()), static_cast<openvdb::GridBase*>(density.get())}) {
    std::ostringstream units;
    units.precision(6);
    if (g == B.get()) units << "tesla";
    else units << "log(|B - applied| / " << low << " T) / log(" << info.reference << " T / " << low << " T), clamped to [0, 1]";
    g->insertMeta("units", openvdb::StringMetadata(units.str()));
    g->insertMeta("frame", openvdb::Int32Metadata(info.frame));
    g->insertMeta("time", openvdb::DoubleMetadata(info.time));
    g->insertMeta("scene_hash", openvdb::StringMetadata(info.scene_hash));
  }
  openvdb::GridPtrVec grids{B, density};
  openvdb::MetaMap file_meta;
  file_meta.insertMeta("creator", openvdb::StringMetadata("magbake"));
  file_meta.insertMeta("units", openvdb::StringMetadata("B in tesla, lengths in metres (world space)"));
  file_meta.insertMeta("frame", openvdb::Int32Metadata(info.frame));
  file_meta.insertMeta("time", openvdb::DoubleMetadata(info.time));
  file_meta.insertMeta("scene_hash", openvdb::StringMetadata(info.scene_hash));
  file_meta.insertMeta("scene_name", openvdb::StringMetadata(info.scene_name));
  file_meta.insertMeta("voxel_size", openvdb::DoubleMetadata(s.voxel));
  file_meta.insertMeta("active_threshold_tesla", openvdb::DoubleMetadata(info.threshold));
  file_meta.insertMeta("density_low_tesla", openvdb::DoubleMetadata(low));
  file_meta.insertMeta("density_high_tesla", openvdb::DoubleMetadata(info.reference));
  file_meta.insertMeta("applied_field_tesla", openvdb::Vec3DMetadata(openvdb::Vec3d(s.applied[0], s.applied[1], s.applied[2])));
  // Write under a temporary name, then rename: no partial file under the final name.
  const std::string tmp = path + ".tmp" + std::to_string(::getpid());
  try {
    openvdb::io::File file(tmp);
    file.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write(grids, file_meta);
    file.close();
    // OpenVDB writes through a std::ofstream whose failures it does not check: a full disk gives
    // a truncated file and no error (and reading such a file back can allocate gigabytes). The
    // same archive serialized to a byte counter gives the size the file must have (io::Stream
    // and io::File write the same number of bytes).
    ByteCounter counter;
    std::ostream counted(&counter);
    openvdb::io::Stream stream(counted);
    stream.setCompression(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK);
    stream.write(grids, file_meta);
    std::error_code ec;
    const auto written = std::filesystem::file_size(tmp, ec);
    if (ec || static_cast<std::streamsize>(written) != counter.bytes()) {
      throw std::runtime_error("short write: " + std::to_string(ec ? 0 : written) + " of " +
                               std::to_string(counter.bytes()) + " bytes (disk full?)");
    }
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error("cannot write " + path + ": " + e.what());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw std::runtime_error("cannot write " + path + ": " + ec.message());
  }
  return active;
}

}  // namespace magbake::io
