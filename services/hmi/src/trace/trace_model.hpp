#pragma once
// TraceModel: the Trace tab's model. Opens a CAN log (candump -L, candump default, ASC)
// with trace::loadLog on a worker thread with a progress value, one row per frame with its
// DBC message and decoded signals; exports the log decoded as CSV through trace's one frame
// writer (the text `vcu dbc decode --format csv` writes for the same log); hands one signal
// to the timeline as samples (trace::extractSamples).
// @note GUI thread only (the loader thread hands its result over through a queued call).

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "openvcu/trace/frame_decoder.hpp"
#include "openvcu/trace/log.hpp"
#include "openvcu/trace/sample_ring.hpp"
#endif

namespace openvcu::hmi {

/// The trace viewer's model: one row per frame of the opened log.
class TraceModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(double progress READ progress NOTIFY progressChanged)
  Q_PROPERTY(bool loading READ loading NOTIFY progressChanged)
  Q_PROPERTY(QString fileName READ fileName NOTIFY loaded)
  Q_PROPERTY(QString summary READ summary NOTIFY loaded)
 public:
  /// Frames kept from one log (trace::LoadOptions::maxFrames).
  static constexpr std::size_t MAX_FRAMES = trace::LoadOptions{}.maxFrames;
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
  /// Starts loading `path` (a local path or file: URL); false when a load is running.
  Q_INVOKABLE bool open(const QString& path);
  /// Writes the log decoded as CSV (t,bus,id,ext,msg,signal,raw,physical: one row per
  /// decoded signal, error frames left out); "" or the reason.
  Q_INVOKABLE QString exportCsv(const QString& path) const;
  /// Blocks until a running load has finished (tests).
  void waitUntilLoaded();
  /// "Message.Signal" of every decodable signal of the messages found in the log.
  Q_INVOKABLE QStringList signalNames() const;
  /// The (time from the first frame in s, value) samples of "Message.Signal" in `ring`
  /// (sized to fit); false when the name is unknown. Decodes the matching frames only.
  bool extract(const QString& messageSignal, trace::SampleRing& ring) const;
  /// Seconds from the first to the last frame.
  [[nodiscard]] double duration() const noexcept { return m_log.duration(); }

 Q_SIGNALS:
  void progressChanged();
  void loaded();

 private:
  struct Loaded {
    trace::LoadedLog log;
    std::string openError;
  };
  void finish(std::shared_ptr<Loaded> result);
  [[nodiscard]] QString decoded(std::size_t row) const;
  trace::LoadedLog m_log;
  std::unique_ptr<trace::FrameDecoder> m_decoder;  ///< the configuration's DBC; null without a stack
  std::thread m_worker;
  std::atomic<double> m_progress{0};
  bool m_loading{};
  QTimer m_progressTimer;
  QString m_fileName;
  QString m_summary;
};

}  // namespace openvcu::hmi
