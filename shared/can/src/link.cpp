#include "openvcu/can/link.hpp"

namespace openvcu::can {

std::string_view linkKindName(LinkKind kind) noexcept {
  switch (kind) {
    case LinkKind::SocketCan:
      return "socketcan";
    case LinkKind::Sim:
      return "sim";
    case LinkKind::Replay:
      return "replay";
  }
  return "?";
}

bool passes(std::span<const IdFilter> filters, const Frame& frame) noexcept {
  if (filters.empty() || (frame.flags & FLAG_ERROR) != 0) return true;
  if ((frame.flags & FLAG_RTR) != 0) return false;  // filters accept data frames only, as on socketcan
  const bool extended = frame.extended();
  for (const IdFilter& filter : filters) {
    if (filter.extended == extended && (frame.id & filter.mask) == (filter.id & filter.mask)) return true;
  }
  return false;
}

std::string_view busEventName(BusEventKind kind) noexcept {
  switch (kind) {
    case BusEventKind::LinkUp:
      return "LinkUp";
    case BusEventKind::LinkDown:
      return "LinkDown";
    case BusEventKind::ErrorWarning:
      return "ErrorWarning";
    case BusEventKind::ErrorPassive:
      return "ErrorPassive";
    case BusEventKind::BusOff:
      return "BusOff";
    case BusEventKind::Restarted:
      return "Restarted";
    case BusEventKind::ErrorActive:
      return "ErrorActive";
    case BusEventKind::RxOverflow:
      return "RxOverflow";
    case BusEventKind::TxTimeout:
      return "TxTimeout";
    case BusEventKind::ProtocolError:
      return "ProtocolError";
    case BusEventKind::NoAck:
      return "NoAck";
    case BusEventKind::TransceiverError:
      return "TransceiverError";
    case BusEventKind::ReplayFinished:
      return "ReplayFinished";
    case BusEventKind::ReplayRestarted:
      return "ReplayRestarted";
  }
  return "?";
}

std::string_view sendStatusName(SendStatus status) noexcept {
  switch (status) {
    case SendStatus::Sent:
      return "Sent";
    case SendStatus::Busy:
      return "Busy";
    case SendStatus::Down:
      return "Down";
    case SendStatus::Invalid:
      return "Invalid";
    case SendStatus::NotSupported:
      return "NotSupported";
  }
  return "?";
}

}  // namespace openvcu::can
