#pragma once
// The display logic without Qt, shared with vcu-web: shared/display (openvcu::display).
// This header brings its names into openvcu::hmi for the Qt models in the screen folders
// (header/, vehicle/, dashboard/, can/, setup/, debug/), which wrap them.

#include "openvcu/display/commands.hpp"
#include "openvcu/display/fsm_rules.hpp"
#include "openvcu/display/health.hpp"
#include "openvcu/display/log_buffer.hpp"
#include "openvcu/display/values.hpp"
#include "openvcu/service/logger.hpp"
#include "openvcu/signals/catalog.hpp"

namespace openvcu::hmi {

/// Short name for the signals namespace in the Qt headers (moc reads `signals` as a keyword).
namespace sig = openvcu::signals;

using display::classify;
using display::CommandOutcome;
using display::CommandTracker;
using display::formatValue;
using display::FsmRules;
using display::HealthTracker;
using display::HeartbeatSlots;
using display::levelName;
using display::Liveness;
using display::livenessName;
using display::LogBuffer;
using display::ServiceHealth;
using display::shortLabel;
using display::shownValue;
using display::staleAfterFor;
using display::statusName;
using display::TextTone;
using display::toneOf;
using display::ValueStatus;
/// The value-table text of a value (shared/signals).
using signals::valueText;
/// "2026-11-26T06:00:00.123Z" for CLOCK_REALTIME ns: the services' log format.
using service::formatUtc;

}  // namespace openvcu::hmi
