#include "dashboard/dashboard_models.hpp"

#include "common/model_helpers.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/config/catalog.hpp"

namespace openvcu::hmi {

// ---- SignalValue ---------------------------------------------------------------------

SignalValue::SignalValue(QObject* parent) : QObject(parent) {
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::displayTick, this, &SignalValue::refresh);
  }
}

void SignalValue::setKey(const QString& key) {
  if (key == m_key) return;
  m_key = key;
  m_index.reset();
  m_error.clear();
  if (StackConnection* stack = StackConnection::instance(); stack && !key.isEmpty()) {
    const auto found = stack->catalog().find(key.toStdString());
    if (found) {
      m_index = *found;
    } else {
      m_error = toQ(found.error().message);
    }
  }
  Q_EMIT keyChanged();
  refresh();
}

void SignalValue::setStaleAfterMs(double milliseconds) {
  m_staleAfterNs = static_cast<std::int64_t>(milliseconds * 1e6);
  Q_EMIT keyChanged();
}

QString SignalValue::unit() const {
  StackConnection* stack = StackConnection::instance();
  return stack && m_index ? toQ(stack->catalog()[*m_index].unit) : QString();
}
double SignalValue::minimum() const {
  StackConnection* stack = StackConnection::instance();
  return stack && m_index ? stack->catalog()[*m_index].minimum : 0.0;
}
double SignalValue::maximum() const {
  StackConnection* stack = StackConnection::instance();
  return stack && m_index ? stack->catalog()[*m_index].maximum : 0.0;
}

void SignalValue::refresh() {
  ModelStatus::Value status = ModelStatus::NotConnected;
  double value = m_value;
  QString text = QStringLiteral("--");
  if (!m_error.isEmpty()) {
    status = ModelStatus::Error;
  } else if (const auto slot = readSlot(m_index)) {
    status =
        ModelStatus::from(classify(*slot, clock::monotonicNs(),
                                   staleAfterFor(StackConnection::instance()->catalog()[*m_index], m_staleAfterNs)));
    if (const auto shown = shownValue(StackConnection::instance()->catalog()[*m_index], *slot)) {
      value = *shown;
      text = toQ(formatValue(StackConnection::instance()->catalog()[*m_index], value, "%.1f"));
    }
  }
  if (status == m_status && value == m_value && text == m_text) return;
  m_status = status;
  m_value = value;
  m_text = text;
  Q_EMIT changed();
}

// ---- DashboardSettings ---------------------------------------------------------------

DashboardSettings::DashboardSettings(QObject* parent) : QObject(parent) {
  StackConnection* stack = StackConnection::instance();
  if (!stack) {
    m_status = ModelStatus::NotConnected;
    return;
  }
  const std::string& path = stack->settings().dashboardPath;
  if (path.empty()) return;
  auto loaded = config::loadDashboardConfig(path, stack->catalog());
  if (!loaded) {
    m_status = ModelStatus::Error;
    m_error = toQ(loaded.error().toString());
    return;
  }
  m_config = std::move(*loaded);
}

// ---- SignalListModel -----------------------------------------------------------------

SignalListModel::SignalListModel(QObject* parent) : StatusListModel(parent) {
  if (StackConnection* stack = StackConnection::instance()) {
    connect(stack, &StackConnection::displayTick, this, &SignalListModel::refresh);
  }
}

int SignalListModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_rows.size());
}

QVariant SignalListModel::data(const QModelIndex& index, int role) const {
  const Row* row = rowAt(m_rows, index);
  if (!row) return {};
  switch (role) {
    case KeyRole:
      return toQ(row->item.key);
    case LabelRole:
    case Qt::DisplayRole:
      return toQ(row->item.label);
    case TextRole:
      return row->text;
    case StatusRole:
      return static_cast<int>(row->status);
    case ToneRole:
      return static_cast<int>(row->tone);
    case DetailRole: {
      StackConnection* stack = StackConnection::instance();
      if (!stack || !row->index) return QStringLiteral("unknown signal");
      const signals::SignalInfo& info = stack->catalog()[*row->index];
      QString detail = toQ(info.key) + QStringLiteral("\nrange ") + QString::number(info.minimum) +
                       QStringLiteral(" .. ") + QString::number(info.maximum) + QLatin1Char(' ') + toQ(info.unit);
      if (!info.comment.empty()) detail += QLatin1Char('\n') + toQ(info.comment);
      for (const auto& [number, text] : info.valueTexts) {
        detail += QStringLiteral("\n%1 = %2").arg(number).arg(toQ(text));
      }
      detail += QStringLiteral("\nstatus: ") + toQ(std::string(statusName(row->status)));
      return detail;
    }
    default:
      return {};
  }
}

QHash<int, QByteArray> SignalListModel::roleNames() const {
  return {{KeyRole, "key"},   {LabelRole, "label"},  {TextRole, "valueText"}, {StatusRole, "valueStatus"},
          {ToneRole, "tone"}, {DetailRole, "detail"}};
}

QStringList SignalListModel::keys() const {
  QStringList list;
  for (const Row& row : m_rows) list << toQ(row.item.key);
  return list;
}

void SignalListModel::setKeys(const QStringList& keys) {
  std::vector<config::DashboardItem> items;
  for (const QString& key : keys) {
    config::DashboardItem item;
    item.key = key.toStdString();
    item.label = shortLabel(item.key);
    item.format = "%.1f";
    items.push_back(std::move(item));
  }
  m_dashboard = false;
  setRows(std::move(items));
}

void SignalListModel::setDashboard(bool dashboard) {
  m_dashboard = dashboard;
  if (!dashboard) return;
  DashboardSettings settings;
  m_staleAfterNs = static_cast<std::int64_t>(settings.staleAfterMs() * 1e6);
  if (settings.status() == ModelStatus::Error) {
    m_status = ModelStatus::Error;
    m_error = settings.errorString();
    Q_EMIT statusChanged();
  }
  setRows(settings.config().items);
}

void SignalListModel::setRows(std::vector<config::DashboardItem> items) {
  beginResetModel();
  m_rows.clear();
  StackConnection* stack = StackConnection::instance();
  for (config::DashboardItem& item : items) {
    Row row;
    if (stack) row.index = stack->catalog().indexOf(item.key);
    row.item = std::move(item);
    m_rows.push_back(std::move(row));
  }
  endResetModel();
  Q_EMIT keysChanged();
  refresh();
}

void SignalListModel::refresh() {
  StackConnection* stack = StackConnection::instance();
  ModelStatus::Value status = ModelStatus::NotConnected;
  if (stack && stack->table()) status = ModelStatus::Ready;
  if (m_status == ModelStatus::Error) status = ModelStatus::Error;
  const std::int64_t now = clock::monotonicNs();
  bool anyStale = false;
  for (std::size_t i = 0; i < m_rows.size(); ++i) {
    Row& row = m_rows[i];
    QString text = QStringLiteral("--");
    ValueStatus valueStatus = row.index ? ValueStatus::NotConnected : ValueStatus::Error;
    TextTone tone = TextTone::Neutral;
    if (const auto slot = readSlot(row.index)) {
      valueStatus = classify(*slot, now, staleAfterFor(stack->catalog()[*row.index], m_staleAfterNs));
      if (const auto shown = shownValue(stack->catalog()[*row.index], *slot)) {
        signals::SignalInfo info = stack->catalog()[*row.index];
        if (!row.item.unit.empty()) info.unit = row.item.unit;
        const std::string formatted = formatValue(info, *shown, row.item.format);
        text = toQ(formatted);
        if (valueText(info, *shown)) tone = toneOf(formatted);
      }
    }
    if (valueStatus == ValueStatus::Stale) anyStale = true;
    if (text != row.text || valueStatus != row.status || tone != row.tone) {
      row.text = text;
      row.status = valueStatus;
      row.tone = tone;
      const QModelIndex changed = index(static_cast<int>(i));
      Q_EMIT dataChanged(changed, changed, {TextRole, StatusRole, ToneRole});
    }
  }
  if (status == ModelStatus::Ready && anyStale) status = ModelStatus::Stale;
  if (status != m_status) {
    m_status = status;
    Q_EMIT statusChanged();
  }
}

}  // namespace openvcu::hmi
