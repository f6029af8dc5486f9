// Every YAML example in docs/scene-format.md parses and validates.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "scene/load.h"

namespace magbake::scene {
namespace {

TEST(SceneFormatDoc, EveryExampleValidates) {
  const std::string doc_path = std::string(MAGBAKE_SOURCE_DIR) + "/docs/scene-format.md";
  std::ifstream in(doc_path);
  ASSERT_TRUE(in) << doc_path;
  std::string line, block;
  bool inside = false;
  int examples = 0, block_line = 0, n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!inside && line == "```yaml") {
      inside = true;
      block.clear();
      block_line = n + 1;
      continue;
    }
    if (inside && line == "```") {
      inside = false;
      ++examples;
      try {
        // Anchored at the doc's folder: mesh paths in examples are relative to it.
        load_scene_text(block, doc_path);
      } catch (const SceneError& e) {
        ADD_FAILURE() << "example starting at docs/scene-format.md:" << block_line << "\n" << e.what();
      }
      continue;
    }
    if (inside) block += line + "\n";
  }
  EXPECT_GE(examples, 6);
}

}  // namespace
}  // namespace magbake::scene
