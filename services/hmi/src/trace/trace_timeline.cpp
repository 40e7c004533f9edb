#include "trace/trace_timeline.hpp"

#include <algorithm>

namespace openvcu::hmi {

TraceTimeline::TraceTimeline(QQuickItem* parent) : QQuickItem(parent) {
  setFlag(ItemHasContents, true);
}

void TraceTimeline::setTrace(TraceModel* trace) {
  if (trace == m_trace) return;
  if (m_trace) disconnect(m_trace, nullptr, this, nullptr);
  m_trace = trace;
  if (m_trace)
    connect(m_trace, &TraceModel::loaded, this, [this] {
      reload();
      reset();
    });
  reload();
  reset();
}

void TraceTimeline::setKeys(const QStringList& keys) {
  m_keys = keys.mid(0, static_cast<qsizetype>(MAX_PLOT_SERIES));
  reload();
}

QString TraceTimeline::toggleKey(const QString& key) {
  QStringList next = m_keys;
  if (next.contains(key)) {
    next.removeAll(key);
  } else {
    if (next.size() >= static_cast<qsizetype>(MAX_PLOT_SERIES)) {
      return QStringLiteral("at most %1 signals on the timeline").arg(MAX_PLOT_SERIES);
    }
    next << key;
  }
  setKeys(next);
  return {};
}

void TraceTimeline::reload() {
  m_series.clear();
  m_ranges.clear();
  m_legend.clear();
  for (const QString& key : m_keys) {
    auto ring = std::make_unique<trace::SampleRing>();
    if (!m_trace || !m_trace->extract(key, *ring)) continue;
    const trace::ValueRange range = trace::valueRange(*ring).value_or(trace::ValueRange{});
    m_ranges.push_back(range);
    m_legend << key + QStringLiteral(" [%1 .. %2]").arg(range.low, 0, 'g', 4).arg(range.high, 0, 'g', 4);
    m_series.push_back(std::move(ring));
  }
  m_seriesChanged = true;
  Q_EMIT changed();
  update();
}

void TraceTimeline::reset() {
  m_start = 0;
  m_end = m_trace && m_trace->duration() > 0 ? m_trace->duration() : 1;
  Q_EMIT changed();
  update();
}

void TraceTimeline::zoom(double factor, double fraction) {
  const double span = m_end - m_start;
  const double centre = m_start + std::clamp(fraction, 0.0, 1.0) * span;
  const double next = std::clamp(span * factor, 0.001, std::max(1.0, m_trace ? m_trace->duration() : 1.0));
  m_start = centre - (centre - m_start) / span * next;
  m_end = m_start + next;
  Q_EMIT changed();
  update();
}

void TraceTimeline::pan(double fraction) {
  const double shift = (m_end - m_start) * fraction;
  m_start += shift;
  m_end += shift;
  Q_EMIT changed();
  update();
}

QSGNode* TraceTimeline::updatePaintNode(QSGNode* oldNode, UpdatePaintNodeData*) {
  const auto columns = static_cast<std::size_t>(std::max(1.0, width()));
  if (m_scratch.size() < columns * 3) m_scratch.resize(columns * 3);
  return updateLines(*this, oldNode, m_seriesChanged, m_series.size(), m_scratch,
                     [&](std::size_t i, float& base, float& span) {
                       const std::size_t filled = trace::decimate(*m_series[i], m_start, m_end, columns, m_scratch);
                       const auto [low, high] = m_ranges[i];
                       span = high > low ? static_cast<float>(high - low) : 1.0f;
                       base = high > low ? static_cast<float>(low) : static_cast<float>(low) - 0.5f;
                       return filled;
                     });
}

}  // namespace openvcu::hmi
