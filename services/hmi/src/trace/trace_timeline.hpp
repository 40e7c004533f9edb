#pragma once
// TraceTimeline: the Trace tab's timeline of up to four signals of the opened log (samples
// from TraceModel::extract), zoomed and panned by buttons and the mouse wheel.
// @note GUI thread only (updatePaintNode: the render thread, while the GUI thread waits).

#include <QQmlEngine>
#include <QQuickItem>
#include <QString>
#include <QStringList>
#include <memory>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/plot_lines.hpp"
#include "openvcu/trace/sample_ring.hpp"
#include "trace/trace_model.hpp"
#endif

namespace openvcu::hmi {

/// The trace viewer's timeline: up to 4 signals of the opened log as line strips over a
/// zoomable, pannable time window (trace::decimate, as SignalPlot).
class TraceTimeline : public QQuickItem {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(openvcu::hmi::TraceModel* trace READ trace WRITE setTrace NOTIFY changed)
  Q_PROPERTY(QStringList keys READ keys WRITE setKeys NOTIFY changed)
  Q_PROPERTY(double viewStart READ viewStart NOTIFY changed)
  Q_PROPERTY(double viewEnd READ viewEnd NOTIFY changed)
  Q_PROPERTY(QStringList legend READ legend NOTIFY changed)
 public:
  explicit TraceTimeline(QQuickItem* parent = nullptr);
  [[nodiscard]] TraceModel* trace() const noexcept { return m_trace; }
  void setTrace(TraceModel* trace);
  [[nodiscard]] QStringList keys() const { return m_keys; }
  void setKeys(const QStringList& keys);
  [[nodiscard]] double viewStart() const noexcept { return m_start; }
  [[nodiscard]] double viewEnd() const noexcept { return m_end; }
  [[nodiscard]] QStringList legend() const { return m_legend; }
  /// Zooms by `factor` (< 1 in, > 1 out) around the point at `fraction` of the width.
  Q_INVOKABLE void zoom(double factor, double fraction);
  /// Moves the window by `fraction` of its width (negative: earlier).
  Q_INVOKABLE void pan(double fraction);
  /// The whole log.
  Q_INVOKABLE void reset();
  /// Adds `key` if absent (up to 4), else removes it; "" or why not.
  Q_INVOKABLE QString toggleKey(const QString& key);

 Q_SIGNALS:
  void changed();

 protected:
  QSGNode* updatePaintNode(QSGNode* oldNode, UpdatePaintNodeData* data) override;

 private:
  void reload();
  TraceModel* m_trace{nullptr};
  QStringList m_keys;
  QStringList m_legend;
  std::vector<std::unique_ptr<trace::SampleRing>> m_series;
  std::vector<trace::ValueRange> m_ranges;  ///< per series over the whole log
  std::vector<float> m_scratch;
  double m_start{};
  double m_end{1};
  bool m_seriesChanged{true};
};

}  // namespace openvcu::hmi
