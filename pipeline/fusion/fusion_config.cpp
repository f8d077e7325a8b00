#include "pipeline/fusion/fusion_config.h"

#include <cmath>

#include "common/enum_names.h"
#include "common/error.h"
#include "common/yaml_section.h"

namespace cenote::pipeline {

std::vector<ConfigError> FusionConfig::validate() const {
  ConfigErrors errors("fusion");
  errors.check(num_views >= 3 && num_views <= kMaxViews && num_views % 2 == 1, "num_views", num_views,
               "must be odd in [3, " + std::to_string(kMaxViews) + "] (the middle view is the reference)");
  if (support_radius == SupportRadius::kRelative) {
    errors.check(eps > 0.0 && eps < 1.0, "eps", eps, "relative support radius must be in (0, 1) (a fraction of depth)");
  } else {
    errors.check(eps > 0.0 && std::isfinite(eps), "eps", eps, "absolute support radius must be > 0 metres and finite");
  }
  errors.check(min_fused_confidence > 0.0 && std::isfinite(min_fused_confidence), "min_fused_confidence",
               min_fused_confidence, "must be > 0 and finite");
  errors.check(min_input_confidence >= 0.0 && std::isfinite(min_input_confidence), "min_input_confidence",
               min_input_confidence, "must be >= 0 and finite");
  errors.check(max_depth_m > 0.0, "max_depth_m", max_depth_m, "must be > 0 (.inf for no limit)");
  return errors.take();
}

void FusionConfig::read(YamlSection& section) {
  section.read("num_views", num_views);
  section.read("eps", eps);
  section.readName("support_radius", support_radius, parseSupportRadius);
  section.read("min_fused_confidence", min_fused_confidence);
  section.read("min_input_confidence", min_input_confidence);
  section.read("max_depth_m", max_depth_m);
}

constexpr EnumName<SupportRadius> kSupportRadiusNames[] = {{SupportRadius::kRelative, "relative"},
                                                           {SupportRadius::kAbsolute, "absolute"}};

const char* toString(SupportRadius radius) { return enumName(kSupportRadiusNames, radius); }

SupportRadius parseSupportRadius(const std::string& name) {
  return parseEnumName(kSupportRadiusNames, name, "fusion.support_radius = " + name, NameQuotes::kSingle);
}

}  // namespace cenote::pipeline
