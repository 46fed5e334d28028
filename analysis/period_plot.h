// The picture `stex periods --plot` writes, for a user to check a lattice before rendering: the exemplar with
// the lattice's nodes drawn over it (anchored at the exemplar's centre: every cross should sit on the same
// feature of its cell), beside the map of the distance d around the periods (S4 Fig. 10: d with t0 and t1
// lengthened or shortened along their own directions, the periods at the centre, low d dark).
#pragma once
#include <string>
#include <vector>

#include "analysis/cs_lattice.h"
#include "analysis/image_io.h"

namespace stex {

// d on an n x n grid around t: cell (i, j) is t0 + (i - (n - 1) / 2) * step * t0 / |t0|, t1 + (j - (n - 1) / 2)
// * step * t1 / |t1| (row-major, j down). Entries whose lattice is unusable are NaN.
struct DistanceMap {
  Lattice center;
  int n = 0;
  double step = 0.0;
  std::vector<double> d;
};
DistanceMap distance_map(const Image& img, const Lattice& t, int n, double step, const DistanceOptions& o = {});

// Writes the picture (PNG or any format write_image_atomic takes); Error(Output) on failure.
void write_period_plot(const std::string& path, const Image& exemplar, const PeriodEstimate& estimate);

}  // namespace stex
