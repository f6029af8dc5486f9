// Field export shared by `magbake field` and `magbake bake` (outputs.field).
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "cache_export.h"
#include "cli.h"
#include "io/field_volume.h"
#include "magnetics/system.h"

namespace magbake::cli {

/// What to export; unset values come from the cache's outputs.field, then from defaults.
struct FieldRequest {
  std::optional<std::pair<int, int>> frames;  ///< inclusive
  std::string pattern;                        ///< "" = outputs.field.path or <cache>.####.vdb
  std::optional<double> voxel;                ///< m
  std::optional<magnetics::Box3> bounds;      ///< world, m
  std::optional<double> margin;               ///< m (auto bounds); unset: outputs.field.margin, else auto
  bool margin_auto = false;                   ///< auto margin asked for (--margin auto), whatever the scene says
  std::optional<int> every;                   ///< every n-th frame from the shot's first (default outputs.field.every)
  std::optional<double> threshold;            ///< T: voxels where the bodies' field is fainter stay inactive; unset: outputs.field.threshold, else auto
  bool threshold_auto = false;                ///< auto threshold asked for (--threshold auto), whatever the scene says
  double theta = 0.15;                        ///< tree opening angle (error bound, docs/field-volumes.md)
  double max_voxels = 6e7;                    ///< capacity guard
  bool allow_absolute = false;                ///< an absolute outputs.field.path may be used
};

/// The bodies' B at every voxel centre of `samples` (origin, voxel, dims set): the model placed
/// in `s`, without the applied field (samples.applied, set by the caller). Blocks of voxels whose
/// field is provably below `threshold` (sum over bodies of 2 mu0/4pi sum|m| / distance³) are
/// skipped and left NaN.
void evaluate_field_grid(const magnetics::Model& model, const magnetics::State& s, const magnetics::FieldOptions& opt,
                         double threshold, io::FieldSamples& samples);


/// Writes the field volumes of a cache. Exit code (0 ok, 1 failure, 2 bad input, 75 interrupted).
int export_field(const std::string& cache_path, const FieldRequest& request, const Global& g);

}  // namespace magbake::cli
