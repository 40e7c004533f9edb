#include "openvcu/config/gpio.hpp"

#include <algorithm>

#include "openvcu/config/catalog.hpp"
#include "openvcu/config/json.hpp"
#include "openvcu/config/vehicle.hpp"
#include "openvcu/core/text.hpp"

namespace openvcu::config {

std::string_view gpioBackendName(GpioBackend backend) noexcept {
  return backend == GpioBackend::Gpiod ? "gpiod" : "sim";
}

std::string_view lineDirectionName(LineDirection direction) noexcept {
  return direction == LineDirection::Output ? "output" : "input";
}

std::string_view lineBiasName(LineBias bias) noexcept {
  switch (bias) {
    case LineBias::AsIs: return "as-is";
    case LineBias::Disabled: return "disabled";
    case LineBias::PullUp: return "pull-up";
    case LineBias::PullDown: return "pull-down";
  }
  return "?";
}

std::string GpioChip::describe() const { return device.empty() ? "label '" + label + "'" : device; }

std::string GpioLine::describeLine() const {
  return offset ? "offset " + std::to_string(*offset) : "line '" + lineName + "'";
}

const GpioLine* GpioMap::inputBoundTo(std::string_view key) const noexcept {
  for (const GpioLine& line : lines) {
    if (line.direction == LineDirection::Input && line.signal == key) return &line;
  }
  return nullptr;
}

namespace {

bool validLineName(std::string_view name) {
  return !name.empty() && name.size() <= 48 && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

class GpioLoader {
 public:
  GpioLoader(const std::string& path, const std::vector<InternalSignal>& declared) : m_check(path), m_declared(declared) {
    m_map.file = path;
  }

  void run(const Json& root) {
    if (!m_check.isObject(root, "")) return;
    m_check.onlyKeys(root, "", {"backend", "chips", "lines", "comment"});
    if (const auto backend = m_check.string(root, "", "backend", false)) {
      if (*backend == "gpiod") {
        m_map.backend = GpioBackend::Gpiod;
      } else if (*backend != "sim") {
        m_check.error("/backend", "'" + *backend + "': expected \"sim\" or \"gpiod\"");
      }
    }
    chips(root);
    lines(root);
  }

  JsonChecker& check() { return m_check; }
  GpioMap& map() { return m_map; }

 private:
  void chips(const Json& root) {
    const Json* list = m_check.array(root, "", "chips");
    if (!list) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/chips", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"id", "device", "label", "comment"});
      GpioChip chip;
      chip.id = m_check.string(item, path, "id").value_or("");
      chip.device = m_check.string(item, path, "device", false).value_or("");
      chip.label = m_check.string(item, path, "label", false).value_or("");
      if (chip.device.empty() == chip.label.empty()) {
        m_check.error(path, "give exactly one of \"device\" (\"gpiochip0\") and \"label\"");
      }
      for (const GpioChip& other : m_map.chips) {
        if (!chip.id.empty() && other.id == chip.id) m_check.error(path + "/id", "chip '" + chip.id + "' is declared twice");
      }
      m_map.chips.push_back(std::move(chip));
    }
  }

  void lines(const Json& root) {
    const Json* list = m_check.array(root, "", "lines");
    if (!list) return;
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = JsonChecker::join("/lines", i);
      const Json& item = (*list)[i];
      if (!m_check.isObject(item, path)) continue;
      m_check.onlyKeys(item, path, {"name", "chip", "offset", "line", "direction", "activeLow", "bias", "debounce",
                                    "onDelay", "offDelay", "initial", "safe", "signal", "comment"});
      GpioLine line;
      lineName(item, path, line);
      chipAndLine(item, path, line);
      direction(item, path, line);
      line.activeLow = m_check.boolean(item, path, "activeLow", false).value_or(false);
      line.bias = bias(item, path);
      line.comment = m_check.string(item, path, "comment", false).value_or("");
      const bool output = line.direction == LineDirection::Output;
      onlyFor(item, path, output, {"debounce"}, "input");
      onlyFor(item, path, !output, {"onDelay", "offDelay", "initial", "safe"}, "output");
      line.debounceNs = duration(item, path, "debounce");
      line.onDelayNs = duration(item, path, "onDelay");
      line.offDelayNs = duration(item, path, "offDelay");
      line.safe = level(item, path, "safe", false);
      line.initial = level(item, path, "initial", line.safe);
      boundSignal(item, path, line);
      m_map.lines.push_back(std::move(line));
    }
  }

  void lineName(const Json& item, const std::string& path, GpioLine& line) {
    const auto name = m_check.string(item, path, "name");
    if (!name) return;
    if (!validLineName(*name)) m_check.error(path + "/name", "'" + *name + "' must be 1-48 letters, digits or '_'");
    for (const GpioLine& other : m_map.lines) {
      if (other.name == *name) m_check.error(path + "/name", "line '" + *name + "' is declared twice");
    }
    line.name = *name;
  }

  void chipAndLine(const Json& item, const std::string& path, GpioLine& line) {
    if (const auto chip = m_check.string(item, path, "chip")) {
      const auto found = std::find_if(m_map.chips.begin(), m_map.chips.end(),
                                      [&](const GpioChip& candidate) { return candidate.id == *chip; });
      if (found == m_map.chips.end()) {
        std::vector<std::string> ids;
        for (const GpioChip& candidate : m_map.chips) ids.push_back(candidate.id);
        std::string message = "no chip '" + *chip + "' in /chips";
        if (auto suggestion = text::didYouMean(*chip, ids)) message += "; did you mean '" + *suggestion + "'?";
        m_check.error(path + "/chip", std::move(message));
      } else {
        line.chip = static_cast<std::size_t>(found - m_map.chips.begin());
      }
    }
    const Json* offset = m_check.member(item, path, "offset", false);
    line.lineName = m_check.string(item, path, "line", false).value_or("");
    if ((offset != nullptr) == !line.lineName.empty()) {
      m_check.error(path, "give exactly one of \"offset\" (a number) and \"line\" (the line's name on the chip)");
    }
    if (offset != nullptr) {
      if (!offset->is_number_unsigned() || offset->get<std::uint64_t>() > 511) {
        m_check.error(path + "/offset", "must be a whole number from 0 to 511");
      } else {
        line.offset = offset->get<std::uint32_t>();
      }
    }
    for (const GpioLine& other : m_map.lines) {
      const bool same = other.chip == line.chip &&
                        ((line.offset && other.offset == line.offset) ||
                         (!line.lineName.empty() && other.lineName == line.lineName));
      if (same) m_check.error(path, line.describeLine() + " of this chip is already used by line '" + other.name + "'");
    }
  }

  void direction(const Json& item, const std::string& path, GpioLine& line) {
    const auto text = m_check.string(item, path, "direction");
    if (!text) return;
    if (*text == "output") {
      line.direction = LineDirection::Output;
    } else if (*text != "input") {
      m_check.error(path + "/direction", "'" + *text + "': expected \"input\" or \"output\"");
    }
  }

  LineBias bias(const Json& item, const std::string& path) {
    const auto text = m_check.string(item, path, "bias", false);
    if (!text) return LineBias::AsIs;
    for (const LineBias bias : {LineBias::AsIs, LineBias::Disabled, LineBias::PullUp, LineBias::PullDown}) {
      if (*text == lineBiasName(bias)) return bias;
    }
    m_check.error(path + "/bias", "'" + *text + "': expected \"as-is\", \"disabled\", \"pull-up\" or \"pull-down\"");
    return LineBias::AsIs;
  }

  void onlyFor(const Json& item, const std::string& path, bool wrongDirection, std::initializer_list<const char*> keys,
               std::string_view direction) {
    if (!wrongDirection) return;
    for (const char* key : keys) {
      if (item.contains(key)) m_check.error(path + "/" + key, "only an " + std::string(direction) + " line has \"" + key + "\"");
    }
  }

  std::int64_t duration(const Json& item, const std::string& path, std::string_view key) {
    const Json* value = m_check.member(item, path, key, false);
    if (value == nullptr) return 0;
    const auto ns = value->is_string() ? parseDurationNs(value->get<std::string>()) : std::nullopt;
    if (!ns) {
      m_check.error(JsonChecker::join(path, key), "expected " + std::string(DURATION_FORM) + " or \"0s\"");
      return 0;
    }
    return *ns;
  }

  bool level(const Json& item, const std::string& path, std::string_view key, bool fallback) {
    const Json* value = m_check.member(item, path, key, false);
    if (value == nullptr) return fallback;
    if (value->is_boolean()) return value->get<bool>();
    if (value->is_number() && (value->get<double>() == 0 || value->get<double>() == 1)) return value->get<double>() == 1;
    m_check.error(JsonChecker::join(path, key), "expected 0 or 1 (the logical level: 1 = active)");
    return fallback;
  }

  void boundSignal(const Json& item, const std::string& path, GpioLine& line) {
    const auto name = m_check.string(item, path, "signal");
    if (!name) return;
    // "relay.Cl15" or the whole key "internal.relay.Cl15"
    const std::string bare = name->starts_with(INTERNAL_PREFIX) ? name->substr(INTERNAL_PREFIX.size()) : *name;
    const auto found = std::find_if(m_declared.begin(), m_declared.end(),
                                    [&](const InternalSignal& declared) { return declared.name == bare; });
    if (found == m_declared.end()) {
      std::vector<std::string> names;
      for (const InternalSignal& declared : m_declared) names.push_back(declared.name);
      std::string message = "'" + *name + "' is not an internal signal of the configuration (\"internalSignals\" in vehicle.json)";
      if (auto suggestion = text::didYouMean(bare, names)) message += "; did you mean '" + *suggestion + "'?";
      m_check.error(path + "/signal", std::move(message));
      return;
    }
    if (found->minimum > 0 || found->maximum < 1) {
      m_check.error(path + "/signal", "'" + *name + "' must allow 0 and 1 (declare \"min\": 0, \"max\": 1)");
    }
    line.signal = std::string(INTERNAL_PREFIX) + bare;
    for (const GpioLine& other : m_map.lines) {
      if (other.signal == line.signal) {
        m_check.error(path + "/signal", "'" + line.signal + "' is already bound to line '" + other.name + "'");
      }
    }
  }

  JsonChecker m_check;
  const std::vector<InternalSignal>& m_declared;
  GpioMap m_map;
};

}  // namespace

std::optional<GpioMap> loadGpioMap(const std::string& path, const std::vector<InternalSignal>& declared,
                                   std::vector<Error>& diagnostics) {
  auto json = readJsonFile(path);
  if (!json) {
    diagnostics.push_back(json.error());
    return std::nullopt;
  }
  GpioLoader loader(path, declared);
  loader.run(*json);
  const auto& found = loader.check().diagnostics();
  diagnostics.insert(diagnostics.end(), found.begin(), found.end());
  if (!loader.check().ok()) return std::nullopt;
  return std::move(loader.map());
}

}  // namespace openvcu::config
