#pragma once
// TraceStatsModel: the Trace tab's Statistics page (issue 21). Reads one or more CAN logs
// as one timeline (trace::LogTimeline) through trace::TraceStats on a worker thread, with
// the vehicle configuration the HMI runs with (or a DBC file, or none), and shows the
// figures of `vcu trace stats`: one row per message (count, expected cycle, measured
// period mean / p50 / p99 / max, deviation, gaps, missing; `flagged` when it deviates),
// the nodes (TraceNodeModel: frames, bit/s, share of the bus) and the bus load per bus
// (mean, peak, load over time).
//
//   TraceStatsModel { id: stats }
//   stats.compute(["drive1/vehicle.log", "drive1/body.log"])   // "computing", then Ready
//   ListView { model: stats }             // messages: bus, frameId, name, count, meanMs, flagged ...
//   ListView { model: stats.nodes }       // bus, saText, name, frames, bitsPerS, sharePct
//   Repeater { model: stats.buses }       // {bus, loadMeanPct, loadMaxPct, series: [Qt.point(s, %)], seriesMaxPct}
//
// Bad input: a log that cannot be opened sets Error and the reason; malformed lines and
// time going backwards set Stale with their count and the first reasons (file:line); a
// configuration that does not load is reported and the analysis runs without a DBC.
// @note GUI thread only (the worker hands its result over through one queued call).

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <QTimer>
#include <QVariantList>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/status_list_model.hpp"
#include "openvcu/trace/stats.hpp"
#include "openvcu/trace/timeline.hpp"
#endif

namespace openvcu::hmi {

/// The nodes of the last statistics: one row per (bus, source address), by bus and bit/s.
class TraceNodeModel : public QAbstractListModel {
  Q_OBJECT
  QML_ANONYMOUS
 public:
  enum Role { BusRole = Qt::UserRole + 1, SaRole, SaTextRole, NameRole, FramesRole, BitsPerSRole, SharePctRole };
  using QAbstractListModel::QAbstractListModel;
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  void reset(std::vector<trace::NodeStats> nodes);

 private:
  std::vector<trace::NodeStats> m_nodes;
};

/// The Statistics page's model: one row per message of the analysed logs.
class TraceStatsModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(bool computing READ computing NOTIFY progressChanged)
  Q_PROPERTY(qint64 framesRead READ framesRead NOTIFY progressChanged)
  Q_PROPERTY(QStringList paths READ paths NOTIFY computed)
  Q_PROPERTY(QString summary READ summary NOTIFY computed)
  Q_PROPERTY(QString setupPath READ setupPath WRITE setSetupPath NOTIFY setupPathChanged)
  Q_PROPERTY(QVariantList buses READ buses NOTIFY computed)
  Q_PROPERTY(QAbstractListModel* nodes READ nodes CONSTANT)
 public:
  enum Role {
    BusRole = Qt::UserRole + 1,
    FrameIdRole,
    NameRole,
    CountRole,
    ExpectedMsRole,
    CycleSourceRole,
    MeanMsRole,
    P50MsRole,
    P99MsRole,
    MaxMsRole,
    DeviationMsRole,
    GapsRole,
    MissingRole,
    FlaggedRole,
  };
  /// A message is flagged when it has an expected cycle and either missed one (a gap) or
  /// its mean period is off by more than this fraction of the expected cycle.
  static constexpr double DEVIATION_TOLERANCE = 0.10;
  /// Reasons of malformed lines kept for errorString (all are counted).
  static constexpr std::size_t MAX_REPORTED_PROBLEMS = 5;

  explicit TraceStatsModel(QObject* parent = nullptr);
  ~TraceStatsModel() override;
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;

  [[nodiscard]] bool computing() const noexcept { return m_computing; }
  [[nodiscard]] qint64 framesRead() const noexcept { return static_cast<qint64>(m_framesRead.load()); }
  [[nodiscard]] QStringList paths() const { return m_paths; }
  [[nodiscard]] QString summary() const { return m_summary; }
  /// What the analysis knows of the vehicle: a vehicle configuration (*.json), a DBC file
  /// (*.dbc) or "" (none: bus load and nodes only). Default: the configuration the HMI runs with.
  [[nodiscard]] QString setupPath() const { return m_setupPath; }
  void setSetupPath(const QString& path);
  [[nodiscard]] QVariantList buses() const { return m_buses; }
  [[nodiscard]] QAbstractListModel* nodes() noexcept { return &m_nodes; }
  /// The report behind the rows (tests, the screenshot).
  [[nodiscard]] const trace::StatsReport& report() const noexcept { return m_report; }

  /// Starts the statistics of `paths` (local paths or file: URLs) as one timeline. A
  /// running computation is cancelled and this one starts when it has stopped.
  Q_INVOKABLE void compute(const QStringList& paths);
  /// The *.log files of `folder` (what `vcu record` writes: one per bus), sorted; empty
  /// when it is not a folder or has none.
  Q_INVOKABLE static QStringList logsInFolder(const QString& folder);
  /// Blocks until a running computation has finished and its result is shown (tests).
  void waitUntilComputed();

 Q_SIGNALS:
  void progressChanged();
  void computed();
  void setupPathChanged();

 private:
  struct Outcome;
  void start(const QStringList& paths);
  void finish(std::shared_ptr<Outcome> outcome);

  std::vector<trace::MessageStats> m_messages;
  TraceNodeModel m_nodes;
  trace::StatsReport m_report;
  QVariantList m_buses;
  QStringList m_paths;
  QStringList m_pending;  ///< asked for while a computation was running
  bool m_hasPending{};
  QString m_summary;
  QString m_setupPath;
  std::shared_ptr<const trace::AnalysisSetup> m_setup;  ///< loaded from m_setupPath, kept between runs
  std::string m_setupLoadedFrom;
  std::thread m_worker;
  std::atomic<bool> m_cancel{false};
  std::atomic<std::uint64_t> m_framesRead{0};
  bool m_computing{};
  QTimer m_progressTimer;
};

}  // namespace openvcu::hmi
