// Random inputs shared by the tests.
#pragma once

#include <random>

#include "magnetics/types.h"

namespace magbake::testing {

/// A direction uniformly distributed on the unit sphere.
inline magnetics::Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return magnetics::Vec3(n(rng), n(rng), n(rng)).normalized();
}

}  // namespace magbake::testing
