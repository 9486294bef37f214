// Tile residency of mip levels (texture/mipmap.h, docs/texture_lod.md): lookups read the
// frame's tiles of the finest used level and the next coarser level elsewhere, whatever
// an earlier frame left resident; the recorder flags the tiles lookups fall in.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "texture/footprint.h"
#include "texture/mipmap.h"

#include "image_checks.h"

namespace sg {
namespace {

/// A pyramid of `img` whose dropped levels come back from `whole`, counting the tiles read.
std::shared_ptr<MipMap> sourced(const ImageData& img, const std::shared_ptr<const MipMap>& whole, int* tiles_read) {
  auto m = std::make_shared<MipMap>(img);
  m->set_source([whole](int first, int count) {
    std::vector<std::vector<float>> out;
    for (int l = first; l < first + count; ++l) out.push_back(whole->level_data(l));
    return out;
  });
  m->set_tile_source([whole, tiles_read](int level, const std::vector<TexelRect>& rects) {
    std::vector<std::vector<float>> out;
    const int nc = whole->channels(), w = whole->width(level);
    for (const TexelRect& r : rects) {
      std::vector<float> t;
      for (int y = r.y0; y < r.y1; ++y)
        t.insert(t.end(), whole->level_data(level).begin() + (size_t(y) * w + r.x0) * nc,
                 whole->level_data(level).begin() + (size_t(y) * w + r.x1) * nc);
      out.push_back(std::move(t));
      ++*tiles_read;
    }
    return out;
  });
  return m;
}

bool near(const Color& a, const Color& b) {
  return std::fabs(a.x - b.x) < 1e-6f && std::fabs(a.y - b.y) < 1e-6f && std::fabs(a.z - b.z) < 1e-6f;
}

TEST(MipTiles, LookupsReadUsedTilesAndTheCoarserLevelElsewhere) {
  const ImageData img = random_image(300, 200, 3, 5);  // 5 x 4 tiles, the last ones narrower
  auto whole = std::make_shared<const MipMap>(img);
  int read = 0;
  auto m = sourced(img, whole, &read);
  ASSERT_EQ(m->tiles_x(0), 5);
  ASSERT_EQ(m->tiles_y(0), 4);
  std::vector<uint8_t> used(20, 0);
  used[0] = used[6] = used[7] = used[19] = 1;  // (0,0), (1,1), (2,1), (4,3)
  m->make_resident(3);                          // levels 0..2 dropped
  m->use_tiles(0, used);
  EXPECT_EQ(read, 4);  // only the used tiles were read
  m->drop_unused();
  EXPECT_EQ(m->used_tiles(), 4);
  EXPECT_EQ(m->resident_tiles(), 4);
  EXPECT_EQ(m->resident_bytes(), m->bytes(0, used));
  EXPECT_LT(m->resident_bytes(), whole->bytes(0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.2f, 1.2f);
  int in_tiles = 0, outside = 0;
  for (int i = 0; i < 4000; ++i) {
    const float s = u(rng), t = u(rng);
    // The four taps of the bilinear lookup in level 0 (repeat wrap).
    const float x = (s - std::floor(s)) * 300.f - 0.5f, y = (t - std::floor(t)) * 200.f - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    bool all = true;
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int xi = ((x0 + dx) % 300 + 300) % 300, yi = ((y0 + dy) % 200 + 200) % 200;
        all = all && used[size_t(yi / 64) * 5 + size_t(xi / 64)];
      }
    const Color got = m->bilinear(0, s, t, WrapMode::Repeat);
    const Color expect = whole->bilinear(all ? 0 : 1, s, t, WrapMode::Repeat);
    EXPECT_TRUE(near(got, expect)) << s << " " << t;
    (all ? in_tiles : outside)++;
    // Trilinear lookups between levels 0 and 1 blend the same two reads (lambda = log2 1.5).
    const Color tri = m->lookup(s, t, 1.5f / 300.f, WrapMode::Repeat);
    const float f = std::log2(1.5f);
    const Color blend = m->bilinear(0, s, t, WrapMode::Repeat) * (1.f - f) + whole->bilinear(1, s, t, WrapMode::Repeat) * f;
    EXPECT_TRUE(near(tri, blend)) << s << " " << t;
  }
  EXPECT_GT(in_tiles, 200);
  EXPECT_GT(outside, 2000);
}

TEST(MipTiles, ImagesDependOnTheFramesTilesNotOnHistory) {
  const ImageData img = random_image(256, 256, 1, 9);
  auto whole = std::make_shared<const MipMap>(img);
  int read = 0;
  auto a = sourced(img, whole, &read), b = sourced(img, whole, &read);
  std::vector<uint8_t> first(16, 0), second(16, 0);
  for (int i = 0; i < 16; i += 3) first[size_t(i)] = 1;
  for (int i = 1; i < 16; i += 2) second[size_t(i)] = 1;
  a->make_resident(4);
  b->make_resident(4);
  a->use_tiles(0, first);  // a worker that rendered another frame first (its tiles stay resident)
  a->use_tiles(0, second);
  b->use_tiles(0, second);
  EXPECT_GT(a->resident_tiles(), b->resident_tiles());
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 2000; ++i) {
    const float s = u(rng), t = u(rng), w = 0.5f * u(rng) / 256.f;
    EXPECT_EQ(a->lookup(s, t, w, WrapMode::Clamp).x, b->lookup(s, t, w, WrapMode::Clamp).x);
  }
  // Back to whole levels: every lookup as the whole pyramid's.
  a->use_levels(0);
  for (int i = 0; i < 200; ++i) {
    const float s = u(rng), t = u(rng);
    EXPECT_EQ(a->bilinear(0, s, t, WrapMode::Repeat).x, whole->bilinear(0, s, t, WrapMode::Repeat).x);
  }
  EXPECT_EQ(a->used_tiles(), 0);
}

TEST(MipTiles, BadTileFlagsAreAnError) {
  const ImageData img = random_image(256, 128, 3, 2);
  auto whole = std::make_shared<const MipMap>(img);
  int read = 0;
  auto m = sourced(img, whole, &read);
  EXPECT_THROW(m->use_tiles(0, std::vector<uint8_t>(3, 1)), Error);
  m->use_tiles(0, std::vector<uint8_t>(8, 1));  // every tile: the whole level
  EXPECT_THROW(m->use_tiles(1, std::vector<uint8_t>(8, 1)), Error);  // level 1 has 2 x 1 tiles
  EXPECT_EQ(m->used_tiles(), 0);
}

TEST(MipTiles, RecorderFlagsTheCellsOfALookupWrappedAsTheTextureWraps) {
  const ImageData img = random_image(256, 256, 3, 1);  // 4 x 4 cells
  MipMap mip(img);
  const float identity[4] = {1, 0, 0, 1};
  const Vec2f a(0.5f / 256.f, 0.f), b(0.f, 0.5f / 256.f);  // half a texel: level 0
  auto flagged = [&](WrapMode wrap, Vec2f st) {
    FootprintRecorder r;
    r.record(nullptr, mip, a, b, identity, st, wrap);
    std::vector<int> cells;
    const auto& u = r.by_mip.at(&mip);
    for (size_t i = 0; i < u.cells.at(0).size(); ++i)
      if (u.cells[0][i]) cells.push_back(int(i));
    return cells;
  };
  // Inside cell (1, 2), far from its edges: that cell only.
  EXPECT_EQ(flagged(WrapMode::Repeat, Vec2f(0.37f, 0.62f)), std::vector<int>({9}));
  // At the right edge, row 0: repeat reaches around to column 0, clamp does not.
  EXPECT_EQ(flagged(WrapMode::Repeat, Vec2f(0.9995f, 0.1f)), std::vector<int>({0, 3}));
  EXPECT_EQ(flagged(WrapMode::Clamp, Vec2f(0.9995f, 0.1f)), std::vector<int>({3}));
  EXPECT_EQ(flagged(WrapMode::Mirror, Vec2f(1.0005f, 0.1f)), std::vector<int>({3}));
  // Uvs of tiled meshes far from [0, 1] wrap the same way.
  EXPECT_EQ(flagged(WrapMode::Repeat, Vec2f(1000.37f, -41.38f)), std::vector<int>({9}));
  // The tiles of level 1 (2 x 2 tiles of 64 texels over 128 x 128) that hold a flagged cell.
  FootprintRecorder r;
  r.record(nullptr, mip, a, b, identity, Vec2f(0.37f, 0.62f), WrapMode::Repeat);
  const std::vector<uint8_t> t0 = r.by_mip.at(&mip).tiles(mip, 0), t1 = r.by_mip.at(&mip).tiles(mip, 1);
  EXPECT_EQ(std::count(t0.begin(), t0.end(), 1), 1);  // level 0's tiles are the cells
  EXPECT_EQ(t1.size(), 4u);
  EXPECT_EQ(t1[2], 1);  // tile (0, 1) of level 1 covers cell (1, 2)
  // A lookup that reads level 3 (a footprint of 8 texels) flags level 3's tiles only: level 0's
  // tiles are for lookups fine enough to read level 0.
  FootprintRecorder wide;
  wide.record(nullptr, mip, Vec2f(12.f / 256.f, 0.f), Vec2f(0.f, 12.f / 256.f), identity, Vec2f(0.37f, 0.62f),
              WrapMode::Repeat);
  const auto& w = wide.by_mip.at(&mip);
  EXPECT_TRUE(w.cells.at(0).empty());
  const std::vector<uint8_t> w0 = w.tiles(mip, 0), w3 = w.tiles(mip, 3);
  EXPECT_EQ(std::count(w0.begin(), w0.end(), 1), 0);
  EXPECT_EQ(std::count(w3.begin(), w3.end(), 1), 1);  // level 3 is 32 x 32: one tile
}

}  // namespace
}  // namespace sg
