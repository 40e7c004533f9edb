#include "common/model_helpers.hpp"

#include <QDateTime>

#include "common/stack_connection.hpp"

namespace openvcu::hmi {

QString durationText(std::int64_t nanoseconds) {
  const double seconds = static_cast<double>(nanoseconds) / 1e9;
  if (seconds < 60) return QString::number(seconds, 'f', 1) + QStringLiteral(" s");
  const auto whole = static_cast<qint64>(seconds);
  if (seconds < 3600) return QStringLiteral("%1 min %2 s").arg(whole / 60).arg(whole % 60);
  return QStringLiteral("%1 h %2 min").arg(whole / 3600).arg((whole % 3600) / 60);
}

QString clockText(std::int64_t realtimeNs) {
  return QDateTime::fromMSecsSinceEpoch(realtimeNs / 1'000'000).toString(QStringLiteral("HH:mm:ss.zzz"));
}

QString hexText(std::uint32_t value, int digits) {
  return QStringLiteral("0x%1")
      .arg(value, digits, 16, QLatin1Char('0'))
      .toUpper()
      .replace(QStringLiteral("0X"), QStringLiteral("0x"));
}

std::optional<signals::SlotSnapshot> readSlot(std::optional<signals::SignalIndex> index) {
  StackConnection* stack = StackConnection::instance();
  if (!stack || !index || !stack->table()) return std::nullopt;
  return stack->table()->read(*index);
}

std::optional<FsmRules> loadRules(QString& error) {
  StackConnection* stack = StackConnection::instance();
  if (!stack || stack->config().fsmFile.empty()) return std::nullopt;
  auto rules = FsmRules::load(stack->config().fsmFile);
  if (!rules) {
    error = toQ(rules.error().toString());
    return std::nullopt;
  }
  return std::move(*rules);
}

}  // namespace openvcu::hmi
