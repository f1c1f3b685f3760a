// The live concentration map (shared/gas/live_map): the same estimate as the
// report's ConcentrationMap where both have data, growing with the samples.
#include <gtest/gtest.h>

#include <cmath>

#include "shared/gas/concentration_map.hpp"
#include "shared/gas/live_map.hpp"

using namespace inspect::gas;

TEST(LiveConcentrationMap, MatchesTheBatchMapAlongAPath) {
  // A robot driving along x through a plume centred at (3, 0).
  std::vector<GasSample> samples;
  for (int i = 0; i <= 600; ++i) {
    const double t = i * 0.1, x = t * 0.1, y = 0.3 * std::sin(t * 0.5);
    samples.push_back({t, x, y, 10.0 * std::exp(-((x - 3) * (x - 3) + y * y) / 2.0)});
  }
  MapOptions o;
  o.cell_m = 0.2;
  LiveConcentrationMap live(o);
  for (const auto& s : samples) live.add(s);
  ASSERT_FALSE(live.empty());
  EXPECT_EQ(live.outside(), 0u);
  EXPECT_EQ(live.samples(), samples.size() - 1);  // the first has no time to stand for
  const auto batch = ConcentrationMap::build(samples, boundsAround(samples, 1.0), o);
  int compared = 0;
  double worst = 0;
  for (std::size_t r = 0; r < live.rows(); ++r)
    for (std::size_t c = 0; c < live.cols(); ++c) {
      const double x = live.originX() + (c + 0.5) * live.cellM(), y = live.originY() + (r + 0.5) * live.cellM();
      const double v = live.value(c, r);
      const auto& b = batch.bounds();
      if (std::isnan(v) || x < b.x_min_m || y < b.y_min_m || x > b.x_max_m || y > b.y_max_m) continue;
      const auto bc = static_cast<std::size_t>((x - b.x_min_m) / batch.cellM());
      const auto br = static_cast<std::size_t>((y - b.y_min_m) / batch.cellM());
      if (bc >= batch.cols() || br >= batch.rows() || !batch.hasData(bc, br)) continue;
      worst = std::max(worst, std::fabs(v - batch.value(bc, br)));
      ++compared;
    }
  EXPECT_GT(compared, 100);
  // Same kernel and weights; the live map splats at the nearest cell centre, the batch map bilinearly.
  EXPECT_LT(worst, 0.6);
}

TEST(LiveConcentrationMap, GrowsInChunksAndSkipsNaN) {
  LiveConcentrationMap m(MapOptions{}, 4.0);
  m.add({0, 0, 0, 1});
  m.add({0.1, 0, 0, 1});
  const auto cols = m.cols();
  m.add({0.2, 0, 0, std::nan("")});
  EXPECT_EQ(m.samples(), 1u);
  m.add({0.3, 10, -7, 2});
  EXPECT_GT(m.cols(), cols);
  EXPECT_LE(m.originX(), -1.0);
  EXPECT_LE(m.originY(), -8.0);
  // A cell far from every sample has no data.
  EXPECT_TRUE(std::isnan(m.value(m.cols() - 1, m.rows() - 1)) || m.cols() * m.cellM() < 12.0);
  MapOptions tiny;
  tiny.max_cells = 100;
  LiveConcentrationMap small(tiny);
  small.add({0, 0, 0, 1});
  small.add({0.1, 0, 0, 1});
  EXPECT_EQ(small.outside(), 1u);  // would need more than 100 cells
}
