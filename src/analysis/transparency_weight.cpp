#include "analysis/transparency_weight.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace hapticd::analysis {

TransferFunction felt_weight(const TransferFunction& weight, double felt_from_hz,
                             double sample_period) {
  if (!(std::isfinite(felt_from_hz) && felt_from_hz > 0.0 && felt_from_hz < 0.5 / sample_period)) {
    throw std::invalid_argument(
        "the felt band's lower edge must be above 0 Hz and below the "
        "Nyquist frequency");
  }
  const double p = std::exp(-2.0 * std::numbers::pi * felt_from_hz * sample_period);
  const double g = 0.5 * (1.0 + p);
  const TransferFunction high_pass{{g, -g}, {1.0, -p}};
  return tf_product(weight, tf_product(high_pass, high_pass));
}

}  // namespace hapticd::analysis
