#pragma once
// FrameTraceModel: the raw frame trace of the CAN Data tab. Frames received (can-rx's "rx")
// and sent (can-tx's "tx") on every bus arrive through iceoryx on one waiting thread, which
// copies them into a preallocated ring (one lock per batch, no allocation per frame); the
// model takes what is new at display rate (10 Hz, while `active` and not `paused`), keeps
// the newest SHOWN frames and filters them by ID, PGN and node. Decoded text per shown row
// (trace::FrameDecoder, trace::appendDecodedText).
// @note GUI thread only, except the receiving thread inside.

#include <QAbstractListModel>
#include <QQmlEngine>
#include <QString>
#include <QTimer>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "openvcu/can/frame.hpp"
#include "openvcu/ipc/frame_stream.hpp"
#include "openvcu/trace/frame_decoder.hpp"
#endif

namespace openvcu::hmi {

class FrameTraceModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(bool active READ active WRITE setActive NOTIFY filterChanged)
  Q_PROPERTY(bool paused READ paused WRITE setPaused NOTIFY filterChanged)
  Q_PROPERTY(QString idFilter READ idFilter WRITE setIdFilter NOTIFY filterChanged)
  Q_PROPERTY(QString pgnFilter READ pgnFilter WRITE setPgnFilter NOTIFY filterChanged)
  Q_PROPERTY(QString nodeFilter READ nodeFilter WRITE setNodeFilter NOTIFY filterChanged)
  Q_PROPERTY(double framesPerSecond READ framesPerSecond NOTIFY statusChanged)
 public:
  static constexpr std::size_t RING = 8192;  ///< frames between two display ticks, at most
  static constexpr std::size_t SHOWN = 300;  ///< newest frames kept for the view
  enum Role {
    TimeRole = Qt::UserRole + 1,
    DirectionRole,
    BusRole,
    IdRole,
    BytesRole,
    MessageRole,
    NodeRole,
    DecodedRole
  };

  struct Entry {
    can::Frame frame{};
    std::int64_t monotonicNs{};
    std::uint16_t bus{};
    bool sent{};
  };

  explicit FrameTraceModel(QObject* parent = nullptr);
  ~FrameTraceModel() override;
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] bool active() const noexcept { return m_active; }
  void setActive(bool active);
  [[nodiscard]] bool paused() const noexcept { return m_paused; }
  void setPaused(bool paused);
  [[nodiscard]] QString idFilter() const { return m_idFilter; }
  void setIdFilter(const QString& filter);
  [[nodiscard]] QString pgnFilter() const { return m_pgnFilter; }
  void setPgnFilter(const QString& filter);
  [[nodiscard]] QString nodeFilter() const { return m_nodeFilter; }
  void setNodeFilter(const QString& filter);
  [[nodiscard]] double framesPerSecond() const noexcept { return m_rate; }

  /// Adds frames as the receiving thread does (tests without iceoryx). Thread-safe.
  void push(const Entry* entries, std::size_t count) noexcept;
  /// Takes what arrived since the last call into the shown frames (also on every tick).
  void collect();

 Q_SIGNALS:
  void filterChanged();

 private:
  void connectFrames();
  void receive();
  void refilter();
  [[nodiscard]] bool passes(const Entry& entry) const;
  [[nodiscard]] std::int32_t messageOf(const can::Frame& frame) const noexcept;

  // receiving side (the thread), guarded by m_mutex
  std::mutex m_mutex;
  std::vector<Entry> m_ring;
  std::uint64_t m_written{};
  std::vector<ipc::FrameSubscriber> m_subscribers;
  std::vector<std::pair<std::uint16_t, bool>> m_subscriberInfo;  ///< bus index, sent
  std::thread m_thread;
  std::atomic<bool> m_stop{false};
  // GUI side
  std::uint64_t m_read{};
  std::vector<Entry> m_shown;  ///< ring of SHOWN
  std::size_t m_shownHead{};
  std::size_t m_shownCount{};
  std::vector<std::size_t> m_visible;  ///< newest first, indices into m_shown
  std::unique_ptr<trace::FrameDecoder> m_decoder;  ///< the configuration's DBC; null without a stack
  QTimer m_connectTimer;
  bool m_active{true};
  bool m_paused{};
  QString m_idFilter;
  QString m_pgnFilter;
  QString m_nodeFilter;
  double m_rate{};
  std::uint64_t m_rateCount{};
  std::int64_t m_rateSinceNs{};
};

}  // namespace openvcu::hmi
