// A scene from YAML text with its magnetics model and an initialized Simulator, for sim tests.
#pragma once

#include <memory>
#include <string>

#include "scene/load.h"
#include "scene/scene_magnetics.h"
#include "sim/simulator.h"

namespace magbake::sim {

struct Bake {
  scene::Scene scene;
  magnetics::Model model;
  std::unique_ptr<Simulator> sim;
  explicit Bake(const std::string& yaml) : scene(scene::load_scene_text(yaml, "test.yaml")) {
    model = scene::build_magnetics_model(scene);
    sim = std::make_unique<Simulator>(scene, model);
    sim->initialize();
  }
};

}  // namespace magbake::sim
