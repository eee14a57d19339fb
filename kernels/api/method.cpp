#include "method.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace bokeh {

std::string OptionSpec::flag() const {
  std::string f = "--" + key;
  std::replace(f.begin(), f.end(), '_', '-');
  return f;
}

double OptionSpec::parse(const std::string& text) const {
  if (!choices.empty()) {
    const auto it = std::find(choices.begin(), choices.end(), text);
    if (it == choices.end())
      throw std::invalid_argument(fmt::format("{} '{}' is not one of {}", flag(), text, fmt::join(choices, ", ")));
    return static_cast<double>(it - choices.begin());
  }
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty())
    throw std::invalid_argument(fmt::format("{} '{}' is not a number", flag(), text));
  check(value);
  return value;
}

void OptionSpec::check(double value) const {
  if (!choices.empty()) {
    if (!(value >= 0 && value < static_cast<double>(choices.size()) && value == std::floor(value)))
      throw std::invalid_argument(fmt::format("{}: {} is not one of {}", flag(), value, fmt::join(choices, ", ")));
    return;
  }
  if (!std::isfinite(value) || value < min || value > max)
    throw std::invalid_argument(fmt::format("{} {} is outside [{}, {}]", flag(), value, min, max));
  if (integer && value != std::floor(value)) throw std::invalid_argument(fmt::format("{} {} is not an integer", flag(), value));
}

nlohmann::json OptionSpec::to_json(double value) const {
  if (!choices.empty()) return choices.at(static_cast<std::size_t>(value));
  if (integer) return static_cast<long long>(value);
  return value;
}

double FilterOptions::number(const std::string& key) const {
  const auto it = values.find(key);
  if (it == values.end()) throw std::logic_error("option '" + key + "' is not set (not an option of this method?)");
  return it->second;
}

std::size_t FilterOptions::choice_index(const std::string& key) const {
  const double value = number(key);
  if (!(value >= 0 && value == std::floor(value)))
    throw std::logic_error(fmt::format("option '{}' = {} is not the index of a choice", key, value));
  return static_cast<std::size_t>(value);
}

FilterOptions Method::defaults(const GatherPattern& pattern) const {
  FilterOptions o;
  o.pattern = pattern;
  o.precision = precisions.at(0);
  o.buffer_scale = 1;
  for (const auto& spec : options) o.values[spec.key] = spec.default_value;
  return o;
}

const OptionSpec* Method::option(const std::string& key) const {
  const auto it = std::find_if(options.begin(), options.end(), [&](const OptionSpec& s) { return s.key == key; });
  return it == options.end() ? nullptr : &*it;
}

nlohmann::json Method::options_json(const FilterOptions& o) const {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& spec : options) out[spec.key] = spec.to_json(o.number(spec.key));
  return out;
}

std::string aperture_unsupported(const Method& method, const FilterOptions& options) {
  if (method.aperture_unsupported) return method.aperture_unsupported(options);
  if (options.aperture.is_disc()) return "";
  return fmt::format("{} draws the disc only, not the aperture {}", method.name, options.aperture.name());
}

void check_options(const Method& method, const FilterOptions& options) {
  validate(options.pattern);
  validate(options.aperture);
  if (const std::string why = aperture_unsupported(method, options); !why.empty()) throw std::invalid_argument(why);
  const auto& precisions = method.precisions;
  if (std::find(precisions.begin(), precisions.end(), options.precision) == precisions.end())
    throw std::invalid_argument(fmt::format("method '{}' does not store intermediates as '{}' (it accepts: {})",
                                            method.name, options.precision, fmt::join(precisions, ", ")));
  const auto& scales = method.buffer_scales;
  if (std::find(scales.begin(), scales.end(), options.buffer_scale) == scales.end())
    throw std::invalid_argument(fmt::format("method '{}' has no buffer scale {} (it accepts: {})", method.name,
                                            options.buffer_scale, fmt::join(scales, ", ")));
  for (const auto& spec : method.options) spec.check(options.number(spec.key));
  for (const auto& [key, value] : options.values)
    if (!method.option(key)) throw std::invalid_argument(fmt::format("method '{}' has no option '{}'", method.name, key));
}

}  // namespace bokeh
