#include "registration/robust_loss.h"

#include <algorithm>
#include <cmath>

#include "shape/core/enum_names.h"
#include "shape/core/error.h"

namespace pectus {

namespace {
constexpr EnumNames<RobustLoss, 4> kLossNames{{{RobustLoss::kNone, "none"},
                                               {RobustLoss::kHuber, "huber"},
                                               {RobustLoss::kCauchy, "cauchy"},
                                               {RobustLoss::kTukey, "tukey"}}};
}  // namespace

RobustLoss ParseRobustLoss(const std::string& name) {
  return ParseEnum(kLossNames, name, [&] {
    return "unknown robust loss '" + name + "' (" + ListEnumNames(kLossNames, "", ", ", ", ") + ")";
  });
}

std::string ToString(RobustLoss loss) { return EnumToString(kLossNames, loss); }

double RobustTuningConstant(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::kNone: return 1.0;
    case RobustLoss::kHuber: return 1.345;
    case RobustLoss::kCauchy: return 2.3849;
    case RobustLoss::kTukey: return 4.6851;
  }
  return 1.0;
}

double RobustWeight(RobustLoss loss, double r, double c) {
  const double a = std::abs(r);
  switch (loss) {
    case RobustLoss::kNone: return 1.0;
    case RobustLoss::kHuber: return a <= c ? 1.0 : c / a;
    case RobustLoss::kCauchy: {
      const double u = r / c;
      return 1.0 / (1.0 + u * u);
    }
    case RobustLoss::kTukey: {
      if (a >= c) return 0.0;
      const double u = r / c;
      const double v = 1.0 - u * u;
      return v * v;
    }
  }
  return 1.0;
}

double MadScale(std::vector<double>* abs_residuals) {
  if (abs_residuals->empty()) return 0.0;
  auto mid = abs_residuals->begin() + static_cast<std::ptrdiff_t>(abs_residuals->size() / 2);
  std::nth_element(abs_residuals->begin(), mid, abs_residuals->end());
  return 1.4826 * *mid;
}

}  // namespace pectus
