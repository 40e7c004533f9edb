#include "trace/trace_model.hpp"

#include <QCoreApplication>
#include <QMetaObject>
#include <QUrl>

#include "common/model_helpers.hpp"

namespace openvcu::hmi {
namespace {

QString localPath(const QString& pathOrUrl) {
  const QUrl url(pathOrUrl);
  return url.isLocalFile() ? url.toLocalFile() : pathOrUrl;
}

}  // namespace

TraceModel::TraceModel(QObject* parent) : StatusListModel(parent) {
  // the base's status and errorString are notified with loaded(), where this model sets them
  connect(this, &TraceModel::loaded, this, &StatusListModel::statusChanged);
  if (StackConnection* stack = StackConnection::instance()) {
    m_decoder = std::make_unique<trace::FrameDecoder>(stack->config().database, dbc::MatchMode::J1939);
  }
  m_progressTimer.setInterval(100);
  connect(&m_progressTimer, &QTimer::timeout, this, &TraceModel::progressChanged);
}

TraceModel::~TraceModel() {
  waitUntilLoaded();
}

void TraceModel::waitUntilLoaded() {
  if (m_worker.joinable()) m_worker.join();
  QCoreApplication::sendPostedEvents(this);
}

bool TraceModel::open(const QString& pathOrUrl) {
  if (m_loading) return false;
  if (m_worker.joinable()) m_worker.join();
  const QString path = localPath(pathOrUrl);
  m_fileName = path;
  m_loading = true;
  m_progress = 0;
  m_progressTimer.start();
  Q_EMIT progressChanged();
  const std::string file = path.toStdString();
  const dbc::MessageMatcher matcher = m_decoder ? m_decoder->matcher() : dbc::MessageMatcher();
  m_worker = std::thread([this, file, matcher] {
    auto result = std::make_shared<Loaded>();
    auto loadResult = trace::loadLog(file, matcher, {.maxFrames = MAX_FRAMES, .progress = &m_progress});
    if (loadResult) {
      result->log = std::move(*loadResult);
    } else {
      result->openError = loadResult.error().toString();
    }
    m_progress = 1.0;
    QMetaObject::invokeMethod(
        this, [this, result] { finish(result); }, Qt::QueuedConnection);
  });
  return true;
}

void TraceModel::finish(std::shared_ptr<Loaded> result) {
  m_progressTimer.stop();
  beginResetModel();
  m_log = std::move(result->log);
  endResetModel();
  m_loading = false;
  if (!result->openError.empty()) {
    m_status = ModelStatus::Error;
    m_error = QString::fromStdString(result->openError);
    m_summary.clear();
  } else {
    m_status = m_log.malformedLines > 0 ? ModelStatus::Stale : ModelStatus::Ready;
    m_error = m_log.malformedLines > 0 ? QStringLiteral("%1 malformed line(s), last: %2")
                                             .arg(m_log.malformedLines)
                                             .arg(QString::fromStdString(m_log.lastError))
                                       : QString();
    m_summary = QStringLiteral("%1 frames, %2 matched to the DBC%3")
                    .arg(m_log.frames.size())
                    .arg(m_log.matchedCount())
                    .arg(m_log.truncated ? QStringLiteral(" (truncated at %1)").arg(MAX_FRAMES) : QString());
  }
  Q_EMIT progressChanged();
  Q_EMIT loaded();
}

int TraceModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_log.frames.size());
}

QString TraceModel::decoded(std::size_t row) const {
  const trace::LogFrame& entry = m_log.frames[row];
  if (!m_decoder || entry.message < 0) return {};
  std::string text;
  trace::appendDecodedText(text, m_decoder->database().messages[static_cast<std::size_t>(entry.message)],
                           m_decoder->decode(entry.frame, entry.message));
  return QString::fromStdString(text);
}

QVariant TraceModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const auto row = static_cast<std::size_t>(index.row());
  const trace::LogFrame& entry = m_log.frames[row];
  const can::Frame& frame = entry.frame;
  switch (role) {
    case TimeRole:
      return QString::number(m_log.secondsFromStart(row), 'f', 6);
    case IdRole:
      return QStringLiteral("%1").arg(frame.id, frame.extended() ? 8 : 3, 16, QLatin1Char('0')).toUpper();
    case DataRole: {
      QString bytes;
      for (const std::uint8_t byte : frame.payload())
        bytes += QStringLiteral("%1 ").arg(byte, 2, 16, QLatin1Char('0')).toUpper();
      return bytes.trimmed();
    }
    case MessageRole:
      return m_decoder && entry.message >= 0
                 ? QString::fromStdString(m_decoder->database().messages[static_cast<std::size_t>(entry.message)].name)
                 : QString();
    case ChannelRole:
      return QString::fromStdString(m_log.channels[entry.channel]);
    case DecodedRole:
    case Qt::DisplayRole:
      return decoded(row);
    default:
      return {};
  }
}

QHash<int, QByteArray> TraceModel::roleNames() const {
  return {
      {TimeRole, "time"}, {IdRole, "frameId"}, {DataRole, "bytes"}, {MessageRole, "message"}, {DecodedRole, "decoded"}};
}

QString TraceModel::exportCsv(const QString& pathOrUrl) const {
  if (!m_decoder) return QStringLiteral("no configuration");
  const Status exportResult =
      trace::exportLog(localPath(pathOrUrl).toStdString(), m_log, *m_decoder, trace::DecodeFormat::Csv);
  return exportResult ? QString() : QString::fromStdString(exportResult.error().toString());
}

QStringList TraceModel::signalNames() const {
  QStringList names;
  if (!m_decoder) return names;
  for (const std::string& name : trace::signalNames(m_log, m_decoder->database()))
    names << QString::fromStdString(name);
  return names;
}

bool TraceModel::extract(const QString& messageSignal, trace::SampleRing& ring) const {
  if (!m_decoder || m_log.frames.empty()) return false;
  const auto signal = trace::findSignal(m_decoder->database(), messageSignal.toStdString());
  if (!signal) return false;
  ring = trace::extractSamples(m_log, *m_decoder, *signal);
  return true;
}

}  // namespace openvcu::hmi
