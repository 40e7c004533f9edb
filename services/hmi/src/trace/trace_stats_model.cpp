#include "trace/trace_stats_model.hpp"

#include <QCoreApplication>
#include <QDir>
#include <QFileInfo>
#include <QMetaObject>
#include <QPointF>
#include <QUrl>
#include <QVariantMap>
#include <algorithm>
#include <cmath>

#include "common/model_helpers.hpp"

namespace openvcu::hmi {
namespace {

QString localPath(const QString& pathOrUrl) {
  const QUrl url(pathOrUrl);
  return url.isLocalFile() ? url.toLocalFile() : pathOrUrl;
}

/// The configuration the HMI runs with, "" without a stack.
QString stackConfigPath() {
  StackConnection* stack = StackConnection::instance();
  return stack ? toQ(stack->settings().configPath) : QString();
}

/// Frames between two looks at the cancel flag and two progress updates.
constexpr std::uint64_t CHECK_EVERY_FRAMES = 4096;

}  // namespace

// ---- TraceNodeModel ---------------------------------------------------------------------

int TraceNodeModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_nodes.size());
}

QVariant TraceNodeModel::data(const QModelIndex& index, int role) const {
  const trace::NodeStats* node = rowAt(m_nodes, index);
  if (!node) return {};
  switch (role) {
    case BusRole:
      return toQ(node->bus);
    case SaRole:
      return node->standard ? -1 : static_cast<int>(node->sa);
    case SaTextRole:
      return node->standard ? QStringLiteral("11-bit") : hexText(node->sa, 2);
    case NameRole:
      return toQ(node->name);
    case FramesRole:
      return static_cast<qulonglong>(node->frames);
    case BitsPerSRole:
      return node->bitsPerS;
    case SharePctRole:
      return node->sharePct;
    default:
      return {};
  }
}

QHash<int, QByteArray> TraceNodeModel::roleNames() const {
  return {{BusRole, "bus"},          {SaRole, "sa"},         {SaTextRole, "saText"},
          {NameRole, "name"},        {FramesRole, "frames"}, {BitsPerSRole, "bitsPerS"},
          {SharePctRole, "sharePct"}};
}

void TraceNodeModel::reset(std::vector<trace::NodeStats> nodes) {
  beginResetModel();
  m_nodes = std::move(nodes);
  endResetModel();
}

// ---- TraceStatsModel --------------------------------------------------------------------

/// What the worker hands back to the GUI thread.
struct TraceStatsModel::Outcome {
  QStringList paths;
  trace::StatsReport report;
  std::shared_ptr<const trace::AnalysisSetup> setup;
  std::string setupFrom;              ///< the path the setup was loaded from
  std::string setupError;             ///< the configuration did not load: ran without a DBC
  std::string openError;              ///< a log could not be opened: nothing computed
  std::vector<std::string> problems;  ///< first MAX_REPORTED_PROBLEMS reasons
  std::uint64_t problemCount{};
  std::uint64_t malformedLines{};
  std::uint64_t backwards{};
  std::uint64_t untimed{};
  bool cancelled{};
};

TraceStatsModel::TraceStatsModel(QObject* parent) : StatusListModel(parent), m_setupPath(stackConfigPath()) {
  // the base's status and errorString are notified with computed(), where this model sets them
  connect(this, &TraceStatsModel::computed, this, &StatusListModel::statusChanged);
  m_progressTimer.setInterval(200);
  connect(&m_progressTimer, &QTimer::timeout, this, &TraceStatsModel::progressChanged);
}

TraceStatsModel::~TraceStatsModel() {
  m_cancel = true;
  if (m_worker.joinable()) m_worker.join();
}

void TraceStatsModel::setSetupPath(const QString& path) {
  if (path == m_setupPath) return;
  m_setupPath = path;
  Q_EMIT setupPathChanged();
}

void TraceStatsModel::waitUntilComputed() {
  while (m_computing) {
    if (m_worker.joinable()) m_worker.join();
    QCoreApplication::sendPostedEvents(this);  // finish(), which may start a pending run
  }
}

QStringList TraceStatsModel::logsInFolder(const QString& folder) {
  const QDir dir(localPath(folder));
  if (folder.isEmpty() || !QFileInfo(dir.path()).isDir()) return {};
  QStringList logs;
  for (const QFileInfo& file : dir.entryInfoList({QStringLiteral("*.log")}, QDir::Files | QDir::Readable, QDir::Name))
    logs << file.absoluteFilePath();
  return logs;
}

void TraceStatsModel::compute(const QStringList& paths) {
  if (m_computing) {
    m_cancel = true;
    m_pending = paths;
    m_hasPending = true;
    return;
  }
  start(paths);
}

void TraceStatsModel::start(const QStringList& paths) {
  if (m_worker.joinable()) m_worker.join();  // it has handed its result over already
  m_cancel = false;
  m_framesRead = 0;
  m_computing = true;
  m_progressTimer.start();
  Q_EMIT progressChanged();
  std::vector<std::string> files;
  QStringList local;
  for (const QString& path : paths) {
    local << localPath(path);
    files.push_back(local.back().toStdString());
  }
  const std::string setupFrom = m_setupPath.toStdString();
  std::shared_ptr<const trace::AnalysisSetup> setup = setupFrom == m_setupLoadedFrom ? m_setup : nullptr;
  m_worker = std::thread([this, files, local, setupFrom, setup]() mutable {
    auto outcome = std::make_shared<Outcome>();
    outcome->paths = local;
    outcome->setupFrom = setupFrom;
    if (!setup) {
      Result<trace::AnalysisSetup> loaded = trace::emptySetup();
      if (setupFrom.ends_with(".dbc") || setupFrom.ends_with(".DBC")) {
        loaded = trace::loadSetupFromDbc({setupFrom});
      } else if (!setupFrom.empty()) {
        loaded = trace::loadSetupFromConfig(setupFrom);
      }
      if (!loaded) {
        outcome->setupError = loaded.error().toString();
        loaded = trace::emptySetup();
      }
      setup = std::make_shared<const trace::AnalysisSetup>(std::move(*loaded));
    }
    outcome->setup = setup;
    auto timeline = trace::LogTimeline::open(files, *setup, [&outcome](const Error& error) {
      if (outcome->problems.size() < MAX_REPORTED_PROBLEMS) outcome->problems.push_back(error.toString());
      ++outcome->problemCount;
    });
    if (!timeline) {
      outcome->openError = timeline.error().toString();
    } else {
      trace::TraceStats stats(*setup, timeline->buses());  // the configured bit rates per bus
      trace::TraceFrame frame;
      std::uint64_t frames = 0;
      while (timeline->next(frame)) {
        stats.add(frame);
        if (++frames % CHECK_EVERY_FRAMES == 0) {
          m_framesRead = frames;
          if (m_cancel) {
            outcome->cancelled = true;
            break;
          }
        }
      }
      m_framesRead = frames;
      if (!outcome->cancelled) outcome->report = stats.finish(timeline->buses());
      for (const trace::LogCounts& counts : timeline->counts()) {
        outcome->malformedLines += counts.malformedLines;
        outcome->backwards += counts.backwards;
        outcome->untimed += counts.untimed;
      }
    }
    QMetaObject::invokeMethod(
        this, [this, outcome] { finish(outcome); }, Qt::QueuedConnection);
  });
}

void TraceStatsModel::finish(std::shared_ptr<Outcome> outcome) {
  m_computing = false;
  m_progressTimer.stop();
  m_setup = outcome->setup;
  m_setupLoadedFrom = outcome->setupFrom;
  if (m_hasPending) {  // asked for other logs meanwhile: this result is stale
    m_hasPending = false;
    start(m_pending);
    return;
  }
  m_paths = outcome->paths;
  beginResetModel();
  m_report = std::move(outcome->report);
  m_messages = m_report.messages;
  endResetModel();
  m_nodes.reset(m_report.nodes);
  m_buses.clear();
  for (const trace::BusStats& bus : m_report.buses) {
    QVariantList series;
    series.reserve(static_cast<qsizetype>(bus.loadSeries.size()));
    double seriesMax = 0;  // a bucket (10 ms and up) can be far above the busiest 1 s window
    for (const auto& [seconds, percent] : bus.loadSeries) {
      series << QPointF(seconds, percent);
      seriesMax = std::max(seriesMax, percent);
    }
    m_buses << QVariantMap{{QStringLiteral("bus"), toQ(bus.bus)},
                           {QStringLiteral("bitrate"), bus.bitrate},
                           {QStringLiteral("frames"), static_cast<qulonglong>(bus.frames)},
                           {QStringLiteral("errorFrames"), static_cast<qulonglong>(bus.errorFrames)},
                           {QStringLiteral("durationS"), bus.durationS},
                           {QStringLiteral("loadMeanPct"), bus.loadMeanPct},
                           {QStringLiteral("loadMaxPct"), bus.loadMaxPct},
                           {QStringLiteral("bucketS"), bus.loadBucketS},
                           {QStringLiteral("seriesMaxPct"), seriesMax},
                           {QStringLiteral("series"), series}};
  }
  QStringList notes;
  if (!outcome->setupError.empty()) {
    notes << QStringLiteral("without a DBC (%1)").arg(toQ(outcome->setupError));
  }
  if (!outcome->openError.empty()) {
    m_status = ModelStatus::Error;
    m_error = toQ(outcome->openError);
    m_summary.clear();
  } else {
    if (outcome->malformedLines > 0)
      notes << QStringLiteral("%1 malformed line(s) skipped").arg(outcome->malformedLines);
    if (outcome->untimed > 0) notes << QStringLiteral("%1 line(s) without a time skipped").arg(outcome->untimed);
    if (outcome->backwards > 0)
      notes << QStringLiteral("time went backwards %1 time(s): those intervals not measured").arg(outcome->backwards);
    if (m_report.skippedFrames > 0)
      notes << QStringLiteral("%1 frame(s) of streams beyond %2 not analysed")
                   .arg(m_report.skippedFrames)
                   .arg(trace::MAX_STREAMS);
    for (const std::string& problem : outcome->problems) notes << toQ(problem);
    if (outcome->problemCount > outcome->problems.size())
      notes << QStringLiteral("... %1 more").arg(outcome->problemCount - outcome->problems.size());
    m_status = notes.isEmpty() ? ModelStatus::Ready : ModelStatus::Stale;
    m_error = notes.join(QStringLiteral("; "));
    m_summary = QStringLiteral("%1 frames in %2 s on %3 bus(es): %4 messages, %5 nodes; %6")
                    .arg(m_report.frames)
                    .arg(m_report.durationS, 0, 'f', 1)
                    .arg(m_report.buses.size())
                    .arg(m_report.messages.size())
                    .arg(m_report.nodes.size())
                    .arg(toQ(m_setup->source));
  }
  Q_EMIT progressChanged();
  Q_EMIT computed();
}

int TraceStatsModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_messages.size());
}

QVariant TraceStatsModel::data(const QModelIndex& index, int role) const {
  const trace::MessageStats* message = rowAt(m_messages, index);
  if (!message) return {};
  switch (role) {
    case BusRole:
      return toQ(message->bus);
    case FrameIdRole:
      return hexText(message->id, message->extended ? 8 : 3);
    case NameRole:
      return toQ(message->name);
    case CountRole:
      return static_cast<qulonglong>(message->count);
    case ExpectedMsRole:
      return message->expectedMs;
    case CycleSourceRole:
      switch (message->cycleSource) {
        case trace::CycleSource::Schedule:
          return QStringLiteral("schedule");
        case trace::CycleSource::Attribute:
          return QStringLiteral("DBC");
        case trace::CycleSource::None:
          return QString();
      }
      return QString();
    case MeanMsRole:
      return message->meanMs;
    case P50MsRole:
      return message->p50Ms;
    case P99MsRole:
      return message->p99Ms;
    case MaxMsRole:
      return message->maxMs;
    case DeviationMsRole:
      return message->deviationMs;
    case GapsRole:
      return static_cast<qulonglong>(message->gaps);
    case MissingRole:
      return static_cast<qulonglong>(message->missing);
    case FlaggedRole:
      return message->expectedMs > 0 &&
             (message->gaps > 0 || std::abs(message->deviationMs) > DEVIATION_TOLERANCE * message->expectedMs);
    case Qt::DisplayRole:
      return toQ(message->name.empty() ? std::string("?") : message->name);
    default:
      return {};
  }
}

QHash<int, QByteArray> TraceStatsModel::roleNames() const {
  return {{BusRole, "bus"},
          {FrameIdRole, "frameId"},
          {NameRole, "name"},
          {CountRole, "count"},
          {ExpectedMsRole, "expectedMs"},
          {CycleSourceRole, "cycleSource"},
          {MeanMsRole, "meanMs"},
          {P50MsRole, "p50Ms"},
          {P99MsRole, "p99Ms"},
          {MaxMsRole, "maxMs"},
          {DeviationMsRole, "deviationMs"},
          {GapsRole, "gaps"},
          {MissingRole, "missing"},
          {FlaggedRole, "flagged"}};
}

}  // namespace openvcu::hmi
