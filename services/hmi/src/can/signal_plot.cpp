#include "can/signal_plot.hpp"

#include <algorithm>

#include "common/display_logic.hpp"
#include "openvcu/core/clock.hpp"

namespace openvcu::hmi {
namespace {

double nowSeconds() noexcept {
  return static_cast<double>(clock::monotonicNs()) / 1e9;
}

}  // namespace

SignalPlot::SignalPlot(QQuickItem* parent) : QQuickItem(parent) {
  setFlag(ItemHasContents, true);
  m_timer.setInterval(1000 / SAMPLE_HZ);
  connect(&m_timer, &QTimer::timeout, this, &SignalPlot::sample);
  m_timer.start();
}

void SignalPlot::setKeys(const QStringList& keys) {
  StackConnection* stack = StackConnection::instance();
  m_series.clear();
  m_keys.clear();
  m_error.clear();
  for (const QString& key : keys) {
    if (m_series.size() >= MAX_SERIES) {
      m_error = QStringLiteral("at most %1 signals in one plot").arg(MAX_SERIES);
      break;
    }
    if (!stack) break;
    const auto found = stack->catalog().find(key.toStdString());
    if (!found) {
      m_error = QString::fromStdString(found.error().message);
      continue;
    }
    auto series = std::make_unique<Series>();
    series->index = *found;
    m_series.push_back(std::move(series));
    m_keys << key;
  }
  m_seriesChanged = true;
  Q_EMIT keysChanged();
  updateReadout();
  update();
}

QString SignalPlot::toggleKey(const QString& key) {
  QStringList next = m_keys;
  if (next.contains(key)) {
    next.removeAll(key);
  } else {
    if (next.size() >= static_cast<int>(MAX_SERIES))
      return QStringLiteral("at most %1 signals in one plot").arg(MAX_SERIES);
    next << key;
  }
  setKeys(next);
  return m_error;
}

void SignalPlot::setWindowSeconds(double seconds) {
  m_window = std::clamp(seconds, 10.0, MAX_WINDOW_SECONDS);
  Q_EMIT windowChanged();
  update();
}

void SignalPlot::setPaused(bool paused) {
  if (paused == m_paused) return;
  m_paused = paused;
  m_pausedAt = nowSeconds();
  Q_EMIT pausedChanged();
  update();
}

void SignalPlot::setCursorX(double x) {
  m_cursorX = x;
  updateReadout();
}

void SignalPlot::sample() {
  StackConnection* stack = StackConnection::instance();
  const signals::SignalTable* table = stack ? stack->table() : nullptr;
  ModelStatus::Value status = table ? ModelStatus::Ready : ModelStatus::NotConnected;
  const double now = nowSeconds();
  const std::int64_t nowNs = clock::monotonicNs();
  for (auto& series : m_series) {
    if (!table) break;
    const auto slot = table->read(series->index);
    if (!slot) continue;
    const auto value = shownValue(stack->catalog()[series->index], *slot);
    if (!value) {
      status = ModelStatus::Stale;
      continue;
    }
    if (classify(*slot, nowNs, staleAfterFor(stack->catalog()[series->index], 2'000'000'000)) != ValueStatus::Ready) {
      status = ModelStatus::Stale;
    }
    series->ring.push(now, *value);
  }
  if (status != m_status) {
    m_status = status;
    Q_EMIT readoutChanged();
  }
  if (!m_paused && !m_series.empty()) update();
  if (m_cursorX >= 0 || !m_series.empty()) updateReadout();
}

void SignalPlot::updateReadout() {
  StackConnection* stack = StackConnection::instance();
  const double end = m_paused ? m_pausedAt : nowSeconds();
  QStringList legend;
  QString readout;
  const double cursorTime = m_cursorX >= 0 && width() > 0 ? end - m_window + m_cursorX / width() * m_window : -1;
  for (const auto& series : m_series) {
    if (!stack) break;
    const signals::SignalInfo& info = stack->catalog()[series->index];
    legend << QString::fromStdString(info.key.substr(info.key.rfind('.') + 1)) +
                  QStringLiteral(" [%1 .. %2 %3]")
                      .arg(series->minimum, 0, 'g', 4)
                      .arg(series->maximum, 0, 'g', 4)
                      .arg(QString::fromStdString(info.unit));
    if (cursorTime >= 0 && series->ring.size() > 0) {
      const std::size_t best = trace::sampleAtOrBefore(series->ring, cursorTime).value_or(0);
      readout += QString::fromStdString(info.key.substr(info.key.rfind('.') + 1) + " = " +
                                        formatValue(info, series->ring.value(best), "%.3g")) +
                 QStringLiteral("   ");
    }
  }
  if (cursorTime >= 0) readout = QStringLiteral("t = -%1 s   ").arg(end - cursorTime, 0, 'f', 2) + readout;
  if (legend != m_legend || readout != m_readout) {
    m_legend = legend;
    m_readout = readout;
    Q_EMIT readoutChanged();
  }
}

QSGNode* SignalPlot::updatePaintNode(QSGNode* oldNode, UpdatePaintNodeData*) {
  const auto columns = static_cast<std::size_t>(std::max(1.0, width()));
  if (m_scratch.size() < columns * 3) m_scratch.resize(columns * 3);  // once per width
  const double end = m_paused ? m_pausedAt : nowSeconds();
  const double start = end - m_window;
  return updateLines(*this, oldNode, m_seriesChanged, m_series.size(), m_scratch,
                     [&](std::size_t i, float& base, float& span) {
                       Series& series = *m_series[i];
                       const std::size_t filled = trace::decimate(series.ring, start, end, columns, m_scratch);
                       float low = 0;
                       float high = 0;
                       for (std::size_t c = 0; c < filled; ++c) {
                         low = c == 0 ? m_scratch[c * 3 + 1] : std::min(low, m_scratch[c * 3 + 1]);
                         high = c == 0 ? m_scratch[c * 3 + 2] : std::max(high, m_scratch[c * 3 + 2]);
                       }
                       series.minimum = low;
                       series.maximum = high;
                       span = high > low ? high - low : 1.0f;
                       base = high > low ? low : low - 0.5f;
                       return filled;
                     });
}

}  // namespace openvcu::hmi
