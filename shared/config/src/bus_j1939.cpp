#include "bus_j1939.hpp"

#include <algorithm>
#include <cmath>

#include "openvcu/j1939/address_table.hpp"

namespace openvcu::config {
namespace {

constexpr std::string_view ADDRESS_REASON = "254 is the null address, 255 global";

std::size_t errorCount(const JsonChecker& check) {
  const auto& all = check.diagnostics();
  return static_cast<std::size_t>(
      std::count_if(all.begin(), all.end(), [](const Error& e) { return e.severity == Severity::Error; }));
}

bool isWholeNumberUpTo(const Json& value, double max) {
  if (!value.is_number()) return false;
  const double number = value.get<double>();
  return number >= 0 && number <= max && number == std::floor(number);
}

/// A whole number in 0..max, else an error naming the path, the range and `reason`.
std::optional<std::uint32_t> wholeNumber(JsonChecker& check, const Json& object, const std::string& path,
                                         std::string_view key, std::uint32_t max, bool required,
                                         std::string_view reason) {
  const std::optional<double> value = check.number(object, path, key, required);
  if (!value) return std::nullopt;
  if (!isWholeNumberUpTo(Json(*value), max)) {
    check.error(JsonChecker::join(path, key),
                "must be a whole number 0.." + std::to_string(max) + " (" + std::string(reason) + ")");
    return std::nullopt;
  }
  return static_cast<std::uint32_t>(*value);
}

/// "addressRange": [first, last].
void loadRange(JsonChecker& check, const Json& range, const std::string& path, BusJ1939& config) {
  if (!range.is_array() || range.size() != 2) {
    check.error(path, "must be [first, last], two addresses 0..253");
    return;
  }
  for (std::size_t i = 0; i < 2; ++i) {
    if (!isWholeNumberUpTo(range[i], j1939::MAX_CLAIMABLE_ADDRESS)) {
      check.error(JsonChecker::join(path, i), "must be a whole number 0..253 (" + std::string(ADDRESS_REASON) + ")");
      return;
    }
  }
  const auto first = static_cast<std::uint8_t>(range[0].get<double>());
  const auto last = static_cast<std::uint8_t>(range[1].get<double>());
  if (first > last) {
    check.error(path, "the first address " + std::to_string(first) + " is above the last " + std::to_string(last));
    return;
  }
  config.rangeFirst = first;
  config.rangeLast = last;
}

}  // namespace

void loadJ1939Name(JsonChecker& check, const Json& object, const std::string& path, j1939::Name& name) {
  if (!check.isObject(object, path)) return;
  check.onlyKeys(object, path,
                 {"identityNumber", "manufacturerCode", "ecuInstance", "functionInstance", "function", "vehicleSystem",
                  "vehicleSystemInstance", "industryGroup", "arbitraryAddressCapable", "comment"});
  auto field = [&](std::string_view key, std::uint32_t max, bool required, std::string_view reason) {
    return wholeNumber(check, object, path, key, max, required, reason).value_or(0);
  };
  name.identityNumber = field("identityNumber", j1939::NAME_MAX_IDENTITY_NUMBER, true, "21 bits");
  name.manufacturerCode = static_cast<std::uint16_t>(
      field("manufacturerCode", j1939::NAME_MAX_MANUFACTURER_CODE, true, "11 bits, assigned by SAE"));
  name.ecuInstance = static_cast<std::uint8_t>(field("ecuInstance", j1939::NAME_MAX_ECU_INSTANCE, false, "3 bits"));
  name.functionInstance =
      static_cast<std::uint8_t>(field("functionInstance", j1939::NAME_MAX_FUNCTION_INSTANCE, false, "5 bits"));
  name.function = static_cast<std::uint8_t>(field("function", j1939::NAME_MAX_FUNCTION, true, "8 bits"));
  name.vehicleSystem =
      static_cast<std::uint8_t>(field("vehicleSystem", j1939::NAME_MAX_VEHICLE_SYSTEM, true, "7 bits"));
  name.vehicleSystemInstance = static_cast<std::uint8_t>(
      field("vehicleSystemInstance", j1939::NAME_MAX_VEHICLE_SYSTEM_INSTANCE, false, "4 bits"));
  name.industryGroup =
      static_cast<std::uint8_t>(field("industryGroup", j1939::NAME_MAX_INDUSTRY_GROUP, true, "3 bits"));
  name.arbitraryAddressCapable = check.boolean(object, path, "arbitraryAddressCapable").value_or(false);
}

void loadBusJ1939(const Json& bus, const std::string& busPath, std::optional<std::uint8_t> nodeAddress,
                  JsonChecker& check, std::optional<BusJ1939>& out) {
  const Json* object = check.member(bus, busPath, "j1939", false);
  if (!object) return;
  const std::string path = busPath + "/j1939";
  if (!check.isObject(*object, path)) return;
  const std::size_t errorsBefore = errorCount(check);
  check.onlyKeys(*object, path, {"name", "preferredAddress", "addressRange", "claim", "comment"});
  BusJ1939 config;

  if (const Json* name = check.member(*object, path, "name", true))
    loadJ1939Name(check, *name, path + "/name", config.name);

  if (object->contains("preferredAddress")) {
    config.preferredAddress = static_cast<std::uint8_t>(
        wholeNumber(check, *object, path, "preferredAddress", j1939::MAX_CLAIMABLE_ADDRESS, true, ADDRESS_REASON)
            .value_or(0));
  } else if (nodeAddress) {
    config.preferredAddress = *nodeAddress;
  } else {
    check.error(path + "/preferredAddress",
                "missing, and this VCU's DBC node has no NmStationAddress to default to; give 0..253");
  }

  if (const Json* range = check.member(*object, path, "addressRange", false)) {
    loadRange(check, *range, path + "/addressRange", config);
    if (!config.name.arbitraryAddressCapable && object->contains("name")) {
      check.warning(path + "/addressRange", "not used: the NAME is not arbitraryAddressCapable, so it never moves");
    }
  }

  config.claim = check.boolean(*object, path, "claim", false).value_or(true);

  if (errorCount(check) == errorsBefore) out = config;
}

}  // namespace openvcu::config
