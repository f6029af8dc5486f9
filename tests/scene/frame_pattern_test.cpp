// Output patterns: expanded by our own code, never printf (scene/frame_pattern.h), and output
// paths confined to the output folder (scene/output_path.h).
#include <gtest/gtest.h>

#include "scene/frame_pattern.h"
#include "scene/output_path.h"

namespace magbake::scene {
namespace {

TEST(FramePattern, ExpandsHashesAndZeroPaddedDecimalsLikePrintf) {
  EXPECT_EQ(expand_frame_pattern("out/field.####.vdb", 7), "out/field.0007.vdb");
  EXPECT_EQ(expand_frame_pattern("out/field.####.vdb", 12345), "out/field.12345.vdb");
  EXPECT_EQ(expand_frame_pattern("f.###.vdb", -3), "f.-03.vdb");  // as printf("%03d", -3)
  EXPECT_EQ(expand_frame_pattern("f.%04d.png", 42), "f.0042.png");
  EXPECT_EQ(expand_frame_pattern("f.%d.png", 42), "f.42.png");
  EXPECT_EQ(expand_frame_pattern("100%%/f.%02d.png", 5), "100%/f.05.png");
  EXPECT_EQ(expand_frame_pattern("f.############.vdb", 2147483647), "f.002147483647.vdb");
}

TEST(FramePattern, RefusesEveryOtherFormatAndOverlongFields) {
  for (const char* bad : {"%s.vdb", "%n", "%x.vdb", "%4d.vdb", "%-4d.vdb", "%ld.vdb", "%013d.vdb", "%00d.vdb", "%",
                          "a%", "####.%04d.vdb", "##.##.vdb", "%d%d.vdb", "", "f.vdb", "out/field", "100%%.png"}) {
    EXPECT_TRUE(frame_pattern_error(bad).has_value()) << bad;
  }
  EXPECT_TRUE(frame_pattern_error(std::string(13, '#')).has_value());
  EXPECT_TRUE(frame_pattern_error(std::string("a\0b", 3)).has_value());
  for (const char* good : {"f.####.vdb", "f.%04d.vdb", "f.%d.vdb", "100%%.####.png", "#"}) {
    EXPECT_FALSE(frame_pattern_error(good).has_value()) << good;
  }
}

TEST(OutputPath, StaysInsideTheOutputFolderUnlessAbsoluteIsAllowed) {
  EXPECT_FALSE(output_path_error("out/shot.h5", false));
  EXPECT_TRUE(output_path_error("../shot.h5", false).has_value());
  EXPECT_TRUE(output_path_error("a/../../shot.h5", false).has_value());
  EXPECT_TRUE(output_path_error("a/b/../c.h5", false).has_value());  // no '..' at all: simple to check, simple to state
  EXPECT_TRUE(output_path_error("/tmp/shot.h5", false).has_value());
  EXPECT_FALSE(output_path_error("/tmp/shot.h5", true).has_value());
  EXPECT_FALSE(output_path_error("/tmp/../shot.h5", true).has_value());  // absolute and allowed: the user's choice
  EXPECT_TRUE(scene_name_error("../../x").has_value());
  EXPECT_TRUE(scene_name_error("a/b").has_value());
  EXPECT_TRUE(scene_name_error("..").has_value());
  EXPECT_TRUE(scene_name_error("").has_value());
  EXPECT_TRUE(scene_name_error("a\nb").has_value());
  EXPECT_FALSE(scene_name_error("shot_010.v2").has_value());
}

}  // namespace
}  // namespace magbake::scene
