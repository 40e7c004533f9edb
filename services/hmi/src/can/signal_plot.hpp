#pragma once
// SignalPlot: the CAN Data tab's live plot. A scene-graph item drawing up to four signals of
// the table as line strips, sampled and redrawn on its own timer (60 Hz) into preallocated
// trace::SampleRing rings; a window of 10 s .. 10 min, pause and a cursor readout. Why a
// custom item and not Qt Charts: docs/design/hmi.md.
// @note GUI thread only (updatePaintNode: the render thread, while the GUI thread waits).

#include <QQmlEngine>
#include <QQuickItem>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <memory>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/plot_lines.hpp"
#include "common/stack_connection.hpp"
#include "openvcu/trace/sample_ring.hpp"
#endif

namespace openvcu::hmi {

class SignalPlot : public QQuickItem {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QStringList keys READ keys WRITE setKeys NOTIFY keysChanged)
  Q_PROPERTY(double windowSeconds READ windowSeconds WRITE setWindowSeconds NOTIFY windowChanged)
  Q_PROPERTY(bool paused READ paused WRITE setPaused NOTIFY pausedChanged)
  Q_PROPERTY(double cursorX READ cursorX WRITE setCursorX NOTIFY readoutChanged)
  Q_PROPERTY(QString readout READ readout NOTIFY readoutChanged)
  Q_PROPERTY(QStringList legend READ legend NOTIFY readoutChanged)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY readoutChanged)
  Q_PROPERTY(QString errorString READ errorString NOTIFY keysChanged)
 public:
  static constexpr std::size_t MAX_SERIES = MAX_PLOT_SERIES;
  static constexpr int SAMPLE_HZ = 60;  ///< sampling and redraw: the plot scrolls at display rate
  static constexpr double MAX_WINDOW_SECONDS = 600;

  explicit SignalPlot(QQuickItem* parent = nullptr);
  [[nodiscard]] QStringList keys() const { return m_keys; }
  void setKeys(const QStringList& keys);
  [[nodiscard]] double windowSeconds() const noexcept { return m_window; }
  void setWindowSeconds(double seconds);
  [[nodiscard]] bool paused() const noexcept { return m_paused; }
  void setPaused(bool paused);
  [[nodiscard]] double cursorX() const noexcept { return m_cursorX; }
  void setCursorX(double x);
  [[nodiscard]] QString readout() const { return m_readout; }
  [[nodiscard]] QStringList legend() const { return m_legend; }
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// Adds `key` if absent (up to MAX_SERIES), else removes it; "" or why not.
  Q_INVOKABLE QString toggleKey(const QString& key);
  /// Samples the table now (also on the timer).
  void sample();

 Q_SIGNALS:
  void keysChanged();
  void windowChanged();
  void pausedChanged();
  void readoutChanged();

 protected:
  QSGNode* updatePaintNode(QSGNode* oldNode, UpdatePaintNodeData* data) override;

 private:
  struct Series {
    sig::SignalIndex index{};
    trace::SampleRing ring{static_cast<std::size_t>(MAX_WINDOW_SECONDS * SAMPLE_HZ)};
    std::uint64_t lastUpdates{};
    double minimum{};
    double maximum{};
  };
  void updateReadout();
  QStringList m_keys;
  std::vector<std::unique_ptr<Series>> m_series;
  std::vector<float> m_scratch;
  QTimer m_timer;
  double m_window{30};
  bool m_paused{};
  double m_pausedAt{};
  double m_cursorX{-1};
  QString m_readout;
  QStringList m_legend;
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
  bool m_seriesChanged{true};
};

}  // namespace openvcu::hmi
