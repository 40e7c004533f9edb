#include "can/frame_trace_model.hpp"

#include <unistd.h>

#include <QCoreApplication>
#include <algorithm>
#include <string>

#include "common/model_helpers.hpp"
#include "openvcu/core/clock.hpp"
#include "openvcu/ipc/runtime.hpp"
#include "openvcu/service/options.hpp"
#include "openvcu/ipc/waiter.hpp"
#include "openvcu/j1939/id.hpp"

namespace openvcu::hmi {
namespace {

constexpr auto WAIT_TIMEOUT = std::chrono::milliseconds(200);  // bounds the reaction to a stop

}  // namespace

FrameTraceModel::FrameTraceModel(QObject* parent) : StatusListModel(parent), m_ring(RING), m_shown(SHOWN) {
  m_visible.reserve(SHOWN);
  m_rateSinceNs = clock::monotonicNs();
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  m_decoder = std::make_unique<trace::FrameDecoder>(stack->config().database, dbc::MatchMode::J1939);
  connect(stack, &StackConnection::displayTick, this, &FrameTraceModel::collect);
  if (!stack->settings().frameStreams) {
    m_error = QStringLiteral("raw frames are off (vcu-hmi --no-frames)");
    return;
  }
  m_connectTimer.setInterval(2000);
  connect(&m_connectTimer, &QTimer::timeout, this, &FrameTraceModel::connectFrames);
  m_connectTimer.start();
  connectFrames();
}

FrameTraceModel::~FrameTraceModel() {
  m_stop = true;
  if (m_thread.joinable()) m_thread.join();
}

void FrameTraceModel::connectFrames() {
  StackConnection* stack = StackConnection::instance();
  if (!stack) return;
  if (m_thread.joinable()) {
    if (ipc::Runtime::roudiReplaced()) {
      // iceoryx 2.0 cannot move this process's ports to the new RouDi: main() executes
      // vcu-hmi again in place (same pid, same arguments) once the event loop has ended
      m_status = ModelStatus::Error;
      m_error = QStringLiteral("iox-roudi was restarted: vcu-hmi restarts itself to see frames again");
      Q_EMIT statusChanged();
      m_connectTimer.stop();
      QCoreApplication::exit(static_cast<int>(service::ExitCode::RoudiRestarted));
    }
    return;
  }
  if (!ipc::Runtime::initialized()) {
    if (!ipc::Runtime::roudiReachable()) {
      m_status = ModelStatus::NotConnected;
      m_error = QStringLiteral("iox-roudi is not running: no raw frames");
      Q_EMIT statusChanged();
      return;
    }
    // the pid makes the name unique: several HMIs may watch one stack (cab and bench)
    if (Status initialized =
            ipc::Runtime::init("vcu-hmi." + stack->config().instance + "." + std::to_string(::getpid()));
        !initialized) {
      m_status = ModelStatus::Error;
      m_error = toQ(initialized.error().toString());
      Q_EMIT statusChanged();
      return;
    }
  }
  for (std::size_t bus = 0; bus < stack->config().buses.size(); ++bus) {
    for (const bool sent : {false, true}) {
      auto subscriber =
          ipc::FrameSubscriber::create(ipc::FrameTopic{stack->config().instance, stack->config().buses[bus].name,
                                                       sent ? ipc::FrameStream::Sent : ipc::FrameStream::Received});
      if (!subscriber) {
        m_status = ModelStatus::Error;
        m_error = toQ(subscriber.error().toString());
        Q_EMIT statusChanged();
        m_subscribers.clear();
        m_subscriberInfo.clear();
        return;
      }
      m_subscribers.push_back(std::move(*subscriber));
      m_subscriberInfo.emplace_back(static_cast<std::uint16_t>(bus), sent);
    }
  }
  m_status = ModelStatus::Ready;
  m_error.clear();
  Q_EMIT statusChanged();
  m_thread = std::thread([this] { receive(); });  // the subscribers are used only there from now on
}

void FrameTraceModel::receive() {
  auto waiterResult = ipc::Waiter::create();
  if (!waiterResult) return;
  ipc::Waiter& waiter = *waiterResult;
  for (std::size_t i = 0; i < m_subscribers.size(); ++i) {
    if (!waiter.attach(m_subscribers[i], i)) return;
  }
  constexpr std::size_t BATCH = 64;
  Entry batch[BATCH];
  while (!m_stop) {
    for (const std::uint64_t id : waiter.waitFor(WAIT_TIMEOUT)) {
      ipc::FrameSubscriber& subscriber = m_subscribers[id];
      const auto [bus, sent] = m_subscriberInfo[id];
      std::size_t count = 0;
      while (auto sample = subscriber.take()) {
        batch[count++] = Entry{sample->frame, sample->monotonicNs, bus, sent};
        if (count == BATCH) {
          push(batch, count);
          count = 0;
        }
      }
      if (count > 0) push(batch, count);
    }
  }
}

void FrameTraceModel::push(const Entry* entries, std::size_t count) noexcept {
  const std::lock_guard lock(m_mutex);
  for (std::size_t i = 0; i < count; ++i) m_ring[(m_written + i) % RING] = entries[i];
  m_written += count;
}

void FrameTraceModel::collect() {
  const std::int64_t now = clock::monotonicNs();
  std::uint64_t taken = 0;
  if (m_active && !m_paused) {
    const std::lock_guard lock(m_mutex);
    // frames older than the ring (or than what the view keeps) are skipped, not copied
    const std::uint64_t first =
        std::max({m_read, m_written > RING ? m_written - RING : 0, m_written > SHOWN ? m_written - SHOWN : 0});
    for (std::uint64_t n = first; n < m_written; ++n) {
      m_shown[(m_shownHead + m_shownCount) % SHOWN] = m_ring[n % RING];
      if (m_shownCount < SHOWN) {
        ++m_shownCount;
      } else {
        m_shownHead = (m_shownHead + 1) % SHOWN;
      }
    }
    taken = m_written - m_read;
    m_read = m_written;
  } else {
    const std::lock_guard lock(m_mutex);
    taken = m_written - m_read;
    m_read = m_written;  // paused: what arrives meanwhile is not shown later
  }
  m_rateCount += taken;
  if (now - m_rateSinceNs >= 1'000'000'000) {
    m_rate = static_cast<double>(m_rateCount) * 1e9 / static_cast<double>(now - m_rateSinceNs);
    m_rateCount = 0;
    m_rateSinceNs = now;
    Q_EMIT statusChanged();
  }
  if (taken > 0 && m_active && !m_paused) refilter();
}

std::int32_t FrameTraceModel::messageOf(const can::Frame& frame) const noexcept {
  return m_decoder ? m_decoder->match(frame) : trace::FrameDecoder::NO_MATCH;
}

bool FrameTraceModel::passes(const Entry& entry) const {
  if (!m_idFilter.isEmpty()) {
    const QString id = QString::number(entry.frame.id, 16);
    if (!id.contains(m_idFilter, Qt::CaseInsensitive)) return false;
  }
  if (!m_pgnFilter.isEmpty()) {
    if (!entry.frame.extended()) return false;
    bool ok = false;
    const uint pgn = m_pgnFilter.startsWith(QStringLiteral("0x"), Qt::CaseInsensitive)
                         ? m_pgnFilter.mid(2).toUInt(&ok, 16)
                         : m_pgnFilter.toUInt(&ok, 10);
    if (!ok || j1939::pgnOf(entry.frame.id) != pgn) return false;
  }
  if (!m_nodeFilter.isEmpty()) {
    StackConnection* stack = StackConnection::instance();
    const std::int32_t message = messageOf(entry.frame);
    if (!stack || message < 0) return false;
    const std::string& node = stack->config().database.messages[static_cast<std::size_t>(message)].transmitter;
    if (!toQ(node).contains(m_nodeFilter, Qt::CaseInsensitive)) return false;
  }
  return true;
}

void FrameTraceModel::refilter() {
  beginResetModel();
  m_visible.clear();
  for (std::size_t n = m_shownCount; n-- > 0;) {  // newest first
    const std::size_t index = (m_shownHead + n) % SHOWN;
    if (passes(m_shown[index])) m_visible.push_back(index);
  }
  endResetModel();
}

void FrameTraceModel::setActive(bool active) {
  m_active = active;
  Q_EMIT filterChanged();
}
void FrameTraceModel::setPaused(bool paused) {
  m_paused = paused;
  Q_EMIT filterChanged();
}
void FrameTraceModel::setIdFilter(const QString& filter) {
  m_idFilter = filter.trimmed().startsWith(QStringLiteral("0x"), Qt::CaseInsensitive) ? filter.trimmed().mid(2)
                                                                                      : filter.trimmed();
  refilter();
  Q_EMIT filterChanged();
}
void FrameTraceModel::setPgnFilter(const QString& filter) {
  m_pgnFilter = filter.trimmed();
  refilter();
  Q_EMIT filterChanged();
}
void FrameTraceModel::setNodeFilter(const QString& filter) {
  m_nodeFilter = filter.trimmed();
  refilter();
  Q_EMIT filterChanged();
}

int FrameTraceModel::rowCount(const QModelIndex& parent) const {
  return listRowCount(parent, m_visible.size());
}

QVariant FrameTraceModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const Entry& entry = m_shown[m_visible[static_cast<std::size_t>(index.row())]];
  const can::Frame& frame = entry.frame;
  StackConnection* stack = StackConnection::instance();
  const std::int32_t message = messageOf(frame);
  switch (role) {
    case TimeRole:
      return QString::number(static_cast<double>(entry.monotonicNs) / 1e9, 'f', 3);
    case DirectionRole:
      return entry.sent ? QStringLiteral("Tx") : QStringLiteral("Rx");
    case BusRole:
      return stack && entry.bus < stack->config().buses.size() ? toQ(stack->config().buses[entry.bus].name) : QString();
    case IdRole:
      return QStringLiteral("%1").arg(frame.id, frame.extended() ? 8 : 3, 16, QLatin1Char('0')).toUpper();
    case BytesRole: {
      QString bytes;
      for (const std::uint8_t byte : frame.payload())
        bytes += QStringLiteral("%1 ").arg(byte, 2, 16, QLatin1Char('0')).toUpper();
      return bytes.trimmed();
    }
    case MessageRole:
      return stack && message >= 0 ? toQ(stack->config().database.messages[static_cast<std::size_t>(message)].name)
                                   : QString();
    case NodeRole:
      return stack && message >= 0
                 ? toQ(stack->config().database.messages[static_cast<std::size_t>(message)].transmitter)
                 : QString();
    case DecodedRole: {
      if (!m_decoder || message < 0) return QString();
      std::string text;
      trace::appendDecodedText(text, m_decoder->database().messages[static_cast<std::size_t>(message)],
                               m_decoder->decode(frame, message));
      return toQ(text);
    }
    default:
      return {};
  }
}

QHash<int, QByteArray> FrameTraceModel::roleNames() const {
  return {{TimeRole, "time"},   {DirectionRole, "direction"}, {BusRole, "bus"},   {IdRole, "frameId"},
          {BytesRole, "bytes"}, {MessageRole, "message"},     {NodeRole, "node"}, {DecodedRole, "decoded"}};
}

}  // namespace openvcu::hmi
