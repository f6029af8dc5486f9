#include "scenes.h"

namespace magbake::testing {

int Rig::add(std::unique_ptr<geometry::Shape> shape, const Material& material, const Pose& part) {
  magnetics::BodySpec b;
  b.parts.push_back({shape.get(), part, material});
  shapes.push_back(std::move(shape));
  bodies.push_back(std::move(b));
  return static_cast<int>(bodies.size()) - 1;
}

void Rig::build(double cell_size, int leaf_size) {
  magnetics::BuildSettings bs;
  bs.cell_size = cell_size;
  bs.leaf_size = leaf_size;
  bs.exact_balls = exact_balls;
  bs.grading = grading;
  model = magnetics::build_model(bodies, bs);
  state = magnetics::State{};
  state.resize(model);
}

Material permanent(double J, const magnetics::Vec3& dir) {
  Material m;
  m.kind = MaterialKind::kPermanent;
  m.remanence = J;
  m.direction = dir.normalized();
  return m;
}

Material linear(double chi) {
  Material m;
  m.kind = chi == -1.0 ? MaterialKind::kSuperconductor : MaterialKind::kLinear;
  m.chi = chi;
  return m;
}

}  // namespace magbake::testing
