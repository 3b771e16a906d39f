#pragma once
// Robust statistics of a residual, shared by the events search and the network path's reading.
//
// median_of(x): the upper middle value of x (x[n/2] once sorted; 0 for an empty x), by
//   nth_element: O(n).
// robust_sigma(x, centre) = 1.4826 median |x_j - centre|: the median absolute deviation about
//   `centre`, scaled to a normal distribution's standard deviation (units of x).

#include <vector>

namespace rths::identify {

double median_of(std::vector<double> x);
double robust_sigma(const std::vector<double>& x, double centre);

}  // namespace rths::identify
