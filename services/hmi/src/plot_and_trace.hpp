#pragma once
// SignalPlot: a scene-graph item drawing up to four signals of the table as line strips,
// sampled and redrawn on its own timer (60 Hz) into preallocated rings; a window of 10 s .. 10 min,
// pause and a cursor readout. Why a custom item and not Qt Charts: docs/design/hmi.md.
//
// TraceModel: the trace viewer. Opens a CAN log (candump -L, candump default, ASC) on a
// worker thread with a progress value, matches frames to the DBC, shows frames with their
// decoded signals, and exports the decoded signals as CSV.
// @note GUI thread only (the loader thread hands its result over through a queued call).

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QQuickItem>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "openvcu/can/frame.hpp"
#include "openvcu/dbc/codec.hpp"
#include "openvcu/dbc/matcher.hpp"
#include "stack_connection.hpp"
#endif

namespace openvcu::hmi {

/// A ring of (time, value) samples with a fixed capacity (allocated once).
class SampleRing {
 public:
  explicit SampleRing(std::size_t capacity = 0);
  void push(double timeSeconds, double value) noexcept;
  void clear() noexcept {
    m_size = 0;
    m_head = 0;
  }
  [[nodiscard]] std::size_t size() const noexcept { return m_size; }
  [[nodiscard]] std::size_t capacity() const noexcept { return m_times.size(); }
  /// i-th oldest sample.
  [[nodiscard]] double time(std::size_t i) const noexcept { return m_times[(m_head + i) % m_times.size()]; }
  [[nodiscard]] double value(std::size_t i) const noexcept { return m_values[(m_head + i) % m_values.size()]; }

 private:
  std::vector<double> m_times;
  std::vector<double> m_values;
  std::size_t m_head{};
  std::size_t m_size{};
};

/// Per pixel column the min and max of the samples in [t0, t1), for a line strip of at most
/// 2 * columns vertices. Writes (x, yMin, yMax) triples into `out` (resized once); returns the
/// columns filled. Empty columns are skipped.
std::size_t decimate(const SampleRing& ring, double t0, double t1, std::size_t columns,
                     std::vector<float>& out) noexcept;

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
  static constexpr std::size_t MAX_SERIES = 4;
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
    SampleRing ring{static_cast<std::size_t>(MAX_WINDOW_SECONDS * SAMPLE_HZ)};
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

/// The trace viewer's model: one row per frame of the opened log.
class TraceModel : public QAbstractListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(double progress READ progress NOTIFY progressChanged)
  Q_PROPERTY(bool loading READ loading NOTIFY progressChanged)
  Q_PROPERTY(QString fileName READ fileName NOTIFY loaded)
  Q_PROPERTY(QString summary READ summary NOTIFY loaded)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY loaded)
  Q_PROPERTY(QString errorString READ errorString NOTIFY loaded)
 public:
  /// Frames kept from one log (80 bytes each: 1,000,000 frames = 80 MB).
  static constexpr std::size_t MAX_FRAMES = 1'000'000;
  enum Role { TimeRole = Qt::UserRole + 1, IdRole, DataRole, MessageRole, DecodedRole, ChannelRole };
  explicit TraceModel(QObject* parent = nullptr);
  ~TraceModel() override;
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] double progress() const noexcept { return m_progress.load(); }
  [[nodiscard]] bool loading() const noexcept { return m_loading; }
  [[nodiscard]] QString fileName() const { return m_fileName; }
  [[nodiscard]] QString summary() const { return m_summary; }
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// Starts loading `path` (a local path or file: URL); false when a load is running.
  Q_INVOKABLE bool open(const QString& path);
  /// Writes time,message,signal,value rows for every decoded signal; "" or the reason.
  Q_INVOKABLE QString exportCsv(const QString& path) const;
  /// Blocks until a running load has finished (tests).
  void waitUntilLoaded();
  /// "Message.Signal" of every decodable signal of the messages found in the log.
  Q_INVOKABLE QStringList signalNames() const;
  /// The (time from the first frame in s, value) samples of "Message.Signal" in `ring`
  /// (sized to fit); false when the name is unknown. Decodes the matching frames only.
  bool extract(const QString& messageSignal, SampleRing& ring) const;
  /// Seconds from the first to the last frame.
  [[nodiscard]] double duration() const noexcept;

 Q_SIGNALS:
  void progressChanged();
  void loaded();

 private:
  struct Loaded {
    std::vector<can::Frame> frames;
    std::vector<std::int32_t> messages;  ///< per frame: index into the database, or -1
    std::uint64_t errors{};
    std::string lastError;
    std::string openError;
    bool truncated{};
  };
  void finish(std::shared_ptr<Loaded> result);
  [[nodiscard]] QString decoded(std::size_t row) const;
  std::vector<can::Frame> m_frames;
  std::vector<std::int32_t> m_messages;
  std::unique_ptr<dbc::DatabaseCodec> m_codec;
  dbc::MessageMatcher m_matcher;
  std::thread m_worker;
  std::atomic<double> m_progress{0};
  bool m_loading{};
  QTimer m_progressTimer;
  QString m_fileName;
  QString m_summary;
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

/// The trace viewer's timeline: up to 4 signals of the opened log as line strips over a
/// zoomable, pannable time window (the same per-pixel min/max decimation as SignalPlot).
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
  std::vector<std::unique_ptr<SampleRing>> m_series;
  std::vector<std::pair<double, double>> m_ranges;  ///< min, max per series over the log
  std::vector<float> m_scratch;
  double m_start{};
  double m_end{1};
  bool m_seriesChanged{true};
};

}  // namespace openvcu::hmi
