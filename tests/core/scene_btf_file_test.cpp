// A scene part's btf may name a BTF file (a measured BTF from `prtlab btf import`, or any
// written one), relative to the scene file: the part then shades with that file's values, as it
// would with a generated BTF; a missing file or a light side other than the scene's local grid
// is an error naming the file.
#include <gtest/gtest.h>

#include "prtlab/base/error.h"
#include "prtlab/btf/btf.h"
#include "prtlab/btf/btf_generator.h"
#include "prtlab/btf/btf_materials.h"
#include "prtlab/btf/scene_btfs.h"
#include "prtlab/geometry/scene.h"
#include "prtlab/storage/stage_cache.h"
#include "support/temp_dir.h"

namespace prt {
namespace {

TEST(SceneBtfFile, APartNamingABtfFileShadesWithIt) {
  testing::TempDir dir("scene_btf_file");
  BtfParams p;
  p.resolution = 3;
  p.view_side = 2;
  p.light_side = 3;
  p.supersampling = 1;
  p.geometry_grid = 16;
  const Btf btf = generate_btf(make_btf_material("bumps", 16), p);
  write_btf(btf, dir.path() / "measured.prt");
  SceneDesc desc;
  desc.file = dir.path() / "scene.toml";
  desc.local_grid = 3;
  ScenePart a, b;
  a.name = "a";
  a.btf = "measured.prt";
  b.name = "b";
  b.btf = "measured.prt";
  desc.parts = {a, b};
  StageCache cache(dir.path() / "cache");
  const auto btfs = scene_part_btfs(desc, BtfParams{}, cache);
  ASSERT_EQ(btfs.size(), 2u);
  EXPECT_EQ(btfs[0], btfs[1]);  // read once, shared
  ASSERT_EQ(btfs[0]->value_count(), btf.value_count());
  EXPECT_TRUE(std::equal(btf.data().begin(), btf.data().end(), btfs[0]->data().begin()));

  desc.local_grid = 4;
  EXPECT_THROW((void)scene_part_btfs(desc, BtfParams{}, cache), InputError);
  desc.local_grid = 3;
  desc.parts[0].btf = "missing.prt";
  try {
    (void)scene_part_btfs(desc, BtfParams{}, cache);
    FAIL() << "a missing BTF file must be an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.toml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("missing.prt"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace prt
