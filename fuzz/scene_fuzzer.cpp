// libFuzzer target: the scene loader (YAML parse + every semantic check) on arbitrary bytes.
// Any input must end in a Scene or a SceneError; a crash, sanitizer report, hang or other
// exception is a finding. Mesh paths resolve against a folder that does not exist, so no
// file outside the corpus is read. Run: fuzz/README.md.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scene/load.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > (1u << 16)) return -1;  // scenes are small; the limit keeps iterations fast
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const magbake::scene::Scene s = magbake::scene::load_scene_text(text, "/nonexistent/fuzz.yaml");
    (void)s.steps_per_frame();
  } catch (const magbake::scene::SceneError&) {
  }
  // The cache readers' path: outputs only, from stored scene text.
  std::optional<magbake::scene::FieldOutput> field;
  std::optional<magbake::scene::PreviewOutput> preview;
  (void)magbake::scene::outputs_of_text(text, field, preview);
  return 0;
}
