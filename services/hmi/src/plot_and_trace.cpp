#include "plot_and_trace.hpp"

#include <QFile>
#include <QMetaObject>
#include <QPainter>
#include <QPolygonF>
#include <QQuickWindow>
#include <QSGFlatColorMaterial>
#include <QSGGeometryNode>
#include <QSGRenderNode>
#include <QSGRendererInterface>
#include <QUrl>
#include <algorithm>
#include <cmath>
#include <fstream>

#include "display_logic.hpp"
#include "openvcu/can/log_reader.hpp"
#include "openvcu/config/catalog.hpp"

namespace openvcu::hmi {
namespace {

const QColor SERIES_COLOURS[SignalPlot::MAX_SERIES] = {QColor(0x42, 0xa5, 0xf5), QColor(0xff, 0xa7, 0x26),
                                                       QColor(0x66, 0xbb, 0x6a), QColor(0xec, 0x40, 0x7a)};
constexpr float LINE_MARGIN = 4;
constexpr float LINE_WIDTH = 2;

/// The plot lines where the scene graph has no graphics API (the software adaptation:
/// QT_QPA_PLATFORM=offscreen, QT_QUICK_BACKEND=software), which does not draw geometry
/// nodes: the same strips, painted with the QPainter the software renderer hands out.
class PainterLinesNode : public QSGRenderNode {
 public:
  explicit PainterLinesNode(QQuickWindow* window) : m_window(window) {}

  std::vector<QPolygonF> lines;  ///< one per series; resized in place, so no allocation once warm
  QRectF bounds;

  void render(const RenderState* state) override {
    auto* painter = static_cast<QPainter*>(
        m_window->rendererInterface()->getResource(m_window, QSGRendererInterface::PainterResource));
    if (painter == nullptr) return;
    painter->save();
    if (const QRegion* clip = state->clipRegion(); clip != nullptr && !clip->isEmpty()) {
      painter->setClipRegion(*clip, Qt::ReplaceClip);  // before the transform
    }
    painter->setTransform(matrix()->toTransform());
    painter->setOpacity(inheritedOpacity());
    painter->setRenderHint(QPainter::Antialiasing, false);  // crisp and cheaper, as the GL lines
    for (std::size_t i = 0; i < lines.size(); ++i) {
      // a cosmetic 1-pixel pen: QPainter's stroker makes wider lines ~10x dearer in software
      QPen pen(SERIES_COLOURS[i], 0);
      pen.setCosmetic(true);
      painter->setPen(pen);
      painter->drawPolyline(lines[i]);
    }
    painter->restore();
  }
  [[nodiscard]] StateFlags changedStates() const override { return {}; }
  [[nodiscard]] RenderingFlags flags() const override { return BoundedRectRendering; }
  [[nodiscard]] QRectF rect() const override { return bounds; }

 private:
  QQuickWindow* m_window;
};

/// The scene-graph part of SignalPlot and TraceTimeline: `seriesCount` line strips through
/// each column's low and high value. `columns(i, base, span)` fills `scratch` with series
/// i's decimated columns (x, low, high) and returns how many; values map base..base+span to
/// the item's height. Geometry nodes (one per series, rebuilt when `rebuild`) on OpenGL/RHI,
/// a PainterLinesNode on the software adaptation.
template <typename Columns>
QSGNode* updateLines(QQuickItem& item, QSGNode* oldNode, bool& rebuild, std::size_t seriesCount,
                     const std::vector<float>& scratch, const Columns& columns) {
  const float h = static_cast<float>(item.height());
  const auto y = [h](float value, float base, float span) {
    return h - LINE_MARGIN - (value - base) / span * (h - 2 * LINE_MARGIN);
  };
  QQuickWindow* window = item.window();
  if (window != nullptr && window->rendererInterface()->graphicsApi() == QSGRendererInterface::Software) {
    auto* node = oldNode != nullptr ? static_cast<PainterLinesNode*>(oldNode) : new PainterLinesNode(window);
    node->bounds = QRectF(0, 0, item.width(), item.height());
    node->lines.resize(seriesCount);
    for (std::size_t i = 0; i < seriesCount; ++i) {
      float base = 0;
      float span = 1;
      const std::size_t filled = columns(i, base, span);
      QPolygonF& line = node->lines[i];
      line.resize(static_cast<qsizetype>(filled * 2));
      for (std::size_t c = 0; c < filled; ++c) {
        const auto x = static_cast<qreal>(scratch[c * 3]);
        line[static_cast<qsizetype>(c * 2)] = QPointF(x, y(scratch[c * 3 + 1], base, span));
        line[static_cast<qsizetype>(c * 2 + 1)] = QPointF(x, y(scratch[c * 3 + 2], base, span));
      }
    }
    node->markDirty(QSGNode::DirtyMaterial);
    rebuild = false;
    return node;
  }
  auto* root = oldNode != nullptr ? oldNode : new QSGNode;
  if (rebuild) {
    while (QSGNode* child = root->firstChild()) {
      root->removeChildNode(child);
      delete child;
    }
    for (std::size_t i = 0; i < seriesCount; ++i) {
      auto* node = new QSGGeometryNode;
      auto* geometry = new QSGGeometry(QSGGeometry::defaultAttributes_Point2D(), 0);
      geometry->setDrawingMode(QSGGeometry::DrawLineStrip);
      geometry->setLineWidth(LINE_WIDTH);
      node->setGeometry(geometry);
      node->setFlag(QSGNode::OwnsGeometry);
      auto* material = new QSGFlatColorMaterial;
      material->setColor(SERIES_COLOURS[i]);
      node->setMaterial(material);
      node->setFlag(QSGNode::OwnsMaterial);
      root->appendChildNode(node);
    }
    rebuild = false;
  }
  QSGNode* child = root->firstChild();
  for (std::size_t i = 0; i < seriesCount && child != nullptr; ++i, child = child->nextSibling()) {
    auto* node = static_cast<QSGGeometryNode*>(child);
    float base = 0;
    float span = 1;
    const std::size_t filled = columns(i, base, span);
    QSGGeometry* geometry = node->geometry();
    const int vertices = static_cast<int>(filled * 2);
    if (geometry->vertexCount() != vertices) geometry->allocate(vertices);
    QSGGeometry::Point2D* points = geometry->vertexDataAsPoint2D();
    for (std::size_t c = 0; c < filled; ++c) {
      points[c * 2].set(scratch[c * 3], y(scratch[c * 3 + 1], base, span));
      points[c * 2 + 1].set(scratch[c * 3], y(scratch[c * 3 + 2], base, span));
    }
    node->markDirty(QSGNode::DirtyGeometry);
  }
  return root;
}

double nowSeconds() noexcept {
  return static_cast<double>(signals::monotonicNowNs()) / 1e9;
}

}  // namespace

// ---- SampleRing -----------------------------------------------------------------------------

SampleRing::SampleRing(std::size_t capacity) : m_times(capacity), m_values(capacity) {}

void SampleRing::push(double timeSeconds, double value) noexcept {
  if (m_times.empty()) return;
  const std::size_t capacity = m_times.size();
  const std::size_t slot = (m_head + m_size) % capacity;
  m_times[slot] = timeSeconds;
  m_values[slot] = value;
  if (m_size < capacity) {
    ++m_size;
  } else {
    m_head = (m_head + 1) % capacity;
  }
}

std::size_t decimate(const SampleRing& ring, double t0, double t1, std::size_t columns,
                     std::vector<float>& out) noexcept {
  if (out.size() < columns * 3) return 0;  // the caller sizes it once per width
  if (columns == 0 || !(t1 > t0) || ring.size() == 0) return 0;
  // first sample inside the window (binary search: times are increasing)
  std::size_t low = 0;
  std::size_t high = ring.size();
  while (low < high) {
    const std::size_t mid = (low + high) / 2;
    if (ring.time(mid) < t0) {
      low = mid + 1;
    } else {
      high = mid;
    }
  }
  std::size_t filled = 0;
  long current = -1;
  for (std::size_t i = low; i < ring.size(); ++i) {
    const double t = ring.time(i);
    if (t >= t1) break;
    const double v = ring.value(i);
    const long column = std::min(static_cast<long>(columns) - 1,
                                 static_cast<long>((t - t0) / (t1 - t0) * static_cast<double>(columns)));
    if (column != current) {
      current = column;
      out[filled * 3] = static_cast<float>(column);
      out[filled * 3 + 1] = static_cast<float>(v);
      out[filled * 3 + 2] = static_cast<float>(v);
      ++filled;
    } else {
      out[(filled - 1) * 3 + 1] = std::min(out[(filled - 1) * 3 + 1], static_cast<float>(v));
      out[(filled - 1) * 3 + 2] = std::max(out[(filled - 1) * 3 + 2], static_cast<float>(v));
    }
  }
  return filled;
}

// ---- SignalPlot ------------------------------------------------------------------------------

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
  const std::int64_t nowNs = signals::monotonicNowNs();
  for (auto& series : m_series) {
    if (!table) break;
    const auto slot = table->read(series->index);
    if (!slot) continue;
    const auto value = shownValue(*slot);
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
      // the sample at or before the cursor
      std::size_t best = 0;
      for (std::size_t i = series->ring.size(); i-- > 0;) {
        if (series->ring.time(i) <= cursorTime) {
          best = i;
          break;
        }
      }
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
                       const std::size_t filled = decimate(series.ring, start, end, columns, m_scratch);
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

// ---- TraceModel --------------------------------------------------------------------------------

TraceModel::TraceModel(QObject* parent) : QAbstractListModel(parent) {
  if (StackConnection* stack = StackConnection::instance()) {
    m_codec = std::make_unique<dbc::DatabaseCodec>(stack->config().database);
    m_matcher = dbc::MessageMatcher(stack->config().database, dbc::MatchMode::J1939);
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
  const QUrl url(pathOrUrl);
  const QString path = url.isLocalFile() ? url.toLocalFile() : pathOrUrl;
  m_fileName = path;
  m_loading = true;
  m_progress = 0;
  m_progressTimer.start();
  Q_EMIT progressChanged();
  const std::string file = path.toStdString();
  const dbc::MessageMatcher matcher = m_matcher;
  m_worker = std::thread([this, file, matcher] {
    auto result = std::make_shared<Loaded>();
    // one cheap pass for the line count, so the progress is a fraction
    std::uint64_t lines = 0;
    {
      std::ifstream in(file, std::ios::binary);
      char buffer[65536];
      while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
        lines += static_cast<std::uint64_t>(std::count(buffer, buffer + in.gcount(), '\n'));
        if (!in) break;
      }
    }
    auto reader = can::LogReader::open(file);
    if (!reader) {
      result->openError = reader.error().toString();
    } else {
      while (auto record = reader->next()) {
        if (result->frames.size() >= MAX_FRAMES) {
          result->truncated = true;
          break;
        }
        result->frames.push_back(record->frame);
        result->messages.push_back(matcher.match(record->frame.id, record->frame.extended()));
        if (lines > 0 && (reader->lineCount() & 1023) == 0) {
          m_progress = static_cast<double>(reader->lineCount()) / static_cast<double>(lines);
        }
      }
      result->errors = reader->errorCount();
      if (reader->lastError()) result->lastError = reader->lastError()->toString();
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
  m_frames = std::move(result->frames);
  m_messages = std::move(result->messages);
  endResetModel();
  m_loading = false;
  if (!result->openError.empty()) {
    m_status = ModelStatus::Error;
    m_error = QString::fromStdString(result->openError);
    m_summary.clear();
  } else {
    const auto matched = static_cast<std::size_t>(
        std::count_if(m_messages.begin(), m_messages.end(), [](std::int32_t m) { return m >= 0; }));
    m_status = result->errors > 0 ? ModelStatus::Stale : ModelStatus::Ready;
    m_error = result->errors > 0 ? QStringLiteral("%1 malformed line(s), last: %2")
                                       .arg(result->errors)
                                       .arg(QString::fromStdString(result->lastError))
                                 : QString();
    m_summary = QStringLiteral("%1 frames, %2 matched to the DBC%3")
                    .arg(m_frames.size())
                    .arg(matched)
                    .arg(result->truncated ? QStringLiteral(" (truncated at %1)").arg(MAX_FRAMES) : QString());
  }
  Q_EMIT progressChanged();
  Q_EMIT loaded();
}

int TraceModel::rowCount(const QModelIndex& parent) const {
  return parent.isValid() ? 0 : static_cast<int>(m_frames.size());
}

QString TraceModel::decoded(std::size_t row) const {
  StackConnection* stack = StackConnection::instance();
  const std::int32_t message = m_messages[row];
  if (!stack || message < 0 || !m_codec) return {};
  const dbc::Message& dbcMessage = stack->config().database.messages[static_cast<std::size_t>(message)];
  QString text;
  (*m_codec)[static_cast<std::size_t>(message)].decode(
      m_frames[row].payload(), [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
        const dbc::Signal& signal = dbcMessage.signals[signalIndex];
        text += QString::fromStdString(signal.name) + QLatin1Char('=') + QString::number(value.physical, 'g', 6);
        if (const std::string* description = signal.describe(static_cast<std::int64_t>(value.rawUnsigned))) {
          text += QStringLiteral(" \"") + QString::fromStdString(*description) + QLatin1Char('"');
        } else if (!signal.unit.empty()) {
          text += QLatin1Char(' ') + QString::fromStdString(signal.unit);
        }
        text += QStringLiteral("  ");
      });
  return text;
}

QVariant TraceModel::data(const QModelIndex& index, int role) const {
  if (!index.isValid() || index.row() >= rowCount()) return {};
  const auto row = static_cast<std::size_t>(index.row());
  const can::Frame& frame = m_frames[row];
  switch (role) {
    case TimeRole:
      return QString::number(static_cast<double>(frame.timestampNs - m_frames.front().timestampNs) / 1e9, 'f', 6);
    case IdRole:
      return QStringLiteral("%1").arg(frame.id, frame.extended() ? 8 : 3, 16, QLatin1Char('0')).toUpper();
    case DataRole: {
      QString bytes;
      for (const std::uint8_t byte : frame.payload())
        bytes += QStringLiteral("%1 ").arg(byte, 2, 16, QLatin1Char('0')).toUpper();
      return bytes.trimmed();
    }
    case MessageRole: {
      StackConnection* stack = StackConnection::instance();
      const std::int32_t message = m_messages[row];
      return stack && message >= 0
                 ? QString::fromStdString(stack->config().database.messages[static_cast<std::size_t>(message)].name)
                 : QString();
    }
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
  const QUrl url(pathOrUrl);
  const QString path = url.isLocalFile() ? url.toLocalFile() : pathOrUrl;
  StackConnection* stack = StackConnection::instance();
  if (!stack || !m_codec) return QStringLiteral("no configuration");
  std::ofstream out(path.toStdString());
  if (!out) return path + QStringLiteral(": cannot write");
  out << "time_s,message,signal,value\n";
  for (std::size_t row = 0; row < m_frames.size(); ++row) {
    const std::int32_t message = m_messages[row];
    if (message < 0) continue;
    const dbc::Message& dbcMessage = stack->config().database.messages[static_cast<std::size_t>(message)];
    const double t = static_cast<double>(m_frames[row].timestampNs - m_frames.front().timestampNs) / 1e9;
    (*m_codec)[static_cast<std::size_t>(message)].decode(
        m_frames[row].payload(), [&](std::uint32_t signalIndex, const dbc::DecodedValue& value) {
          out << t << ',' << dbcMessage.name << ',' << dbcMessage.signals[signalIndex].name << ',' << value.physical
              << '\n';
        });
  }
  if (!out) return path + QStringLiteral(": write failed");
  return {};
}

QStringList TraceModel::signalNames() const {
  StackConnection* stack = StackConnection::instance();
  QStringList names;
  if (!stack) return names;
  std::vector<bool> seen(stack->config().database.messages.size());
  for (const std::int32_t message : m_messages) {
    if (message < 0 || seen[static_cast<std::size_t>(message)]) continue;
    seen[static_cast<std::size_t>(message)] = true;
    const dbc::Message& dbcMessage = stack->config().database.messages[static_cast<std::size_t>(message)];
    for (const dbc::Signal& signal : dbcMessage.signals) {
      if (signal.decodable()) names << QString::fromStdString(dbcMessage.name + "." + signal.name);
    }
  }
  names.sort();
  return names;
}

double TraceModel::duration() const noexcept {
  if (m_frames.size() < 2) return 0;
  return static_cast<double>(m_frames.back().timestampNs - m_frames.front().timestampNs) / 1e9;
}

bool TraceModel::extract(const QString& messageSignal, SampleRing& ring) const {
  StackConnection* stack = StackConnection::instance();
  const qsizetype dot = messageSignal.lastIndexOf(QLatin1Char('.'));
  if (!stack || !m_codec || dot <= 0 || m_frames.empty()) return false;
  const std::string messageName = messageSignal.left(dot).toStdString();
  const std::string signalName = messageSignal.mid(dot + 1).toStdString();
  const auto& messages = stack->config().database.messages;
  std::int32_t wanted = -1;
  std::uint32_t signalIndex = 0;
  for (std::size_t m = 0; m < messages.size() && wanted < 0; ++m) {
    if (messages[m].name != messageName) continue;
    for (std::size_t i = 0; i < messages[m].signals.size(); ++i) {
      if (messages[m].signals[i].name == signalName) {
        wanted = static_cast<std::int32_t>(m);
        signalIndex = static_cast<std::uint32_t>(i);
      }
    }
  }
  if (wanted < 0) return false;
  const auto count = static_cast<std::size_t>(std::count(m_messages.begin(), m_messages.end(), wanted));
  ring = SampleRing(count);
  const std::int64_t first = m_frames.front().timestampNs;
  for (std::size_t row = 0; row < m_frames.size(); ++row) {
    if (m_messages[row] != wanted) continue;
    (*m_codec)[static_cast<std::size_t>(wanted)].decode(
        m_frames[row].payload(), [&](std::uint32_t index, const dbc::DecodedValue& value) {
          if (index == signalIndex)
            ring.push(static_cast<double>(m_frames[row].timestampNs - first) / 1e9, value.physical);
        });
  }
  return true;
}

// ---- TraceTimeline ------------------------------------------------------------------------------

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
  m_keys = keys.mid(0, static_cast<qsizetype>(SignalPlot::MAX_SERIES));
  reload();
}

QString TraceTimeline::toggleKey(const QString& key) {
  QStringList next = m_keys;
  if (next.contains(key)) {
    next.removeAll(key);
  } else {
    if (next.size() >= static_cast<qsizetype>(SignalPlot::MAX_SERIES)) {
      return QStringLiteral("at most %1 signals on the timeline").arg(SignalPlot::MAX_SERIES);
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
    auto ring = std::make_unique<SampleRing>();
    if (!m_trace || !m_trace->extract(key, *ring)) continue;
    double low = 0;
    double high = 0;
    for (std::size_t i = 0; i < ring->size(); ++i) {
      low = i == 0 ? ring->value(i) : std::min(low, ring->value(i));
      high = i == 0 ? ring->value(i) : std::max(high, ring->value(i));
    }
    m_ranges.emplace_back(low, high);
    m_legend << key + QStringLiteral(" [%1 .. %2]").arg(low, 0, 'g', 4).arg(high, 0, 'g', 4);
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
                       const std::size_t filled = decimate(*m_series[i], m_start, m_end, columns, m_scratch);
                       const auto [low, high] = m_ranges[i];
                       span = high > low ? static_cast<float>(high - low) : 1.0f;
                       base = high > low ? static_cast<float>(low) : static_cast<float>(low) - 0.5f;
                       return filled;
                     });
}

}  // namespace openvcu::hmi
