#pragma once
// Models that show signal values from the table, read at display rate (StackConnection's
// displayTick), never per CAN frame: one value for a dial or the header (SignalValue), a
// list of values (the dashboard grid and the Vehicle tab's status table: SignalListModel)
// and the dashboard file's dials and tiles (DashboardSettings). Every model has `status`
// (ModelStatus) and `errorString`.
// @note GUI thread only.

#include <QAbstractListModel>
#include <QObject>
#include <QQmlEngine>
#include <QString>
#include <QStringList>
#include <optional>
#include <vector>

#ifndef Q_MOC_RUN  // moc reads "signals" in openvcu::signals as a keyword
#include "common/display_logic.hpp"
#include "common/stack_connection.hpp"
#include "common/status_list_model.hpp"
#include "openvcu/config/dashboard.hpp"
#endif

namespace openvcu::hmi {

/// One signal for a dial or the header. QML: SignalValue { key: "VIC...HS_FastUpdSOC" }.
class SignalValue : public QObject {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString key READ key WRITE setKey NOTIFY keyChanged)
  Q_PROPERTY(double staleAfterMs READ staleAfterMs WRITE setStaleAfterMs NOTIFY keyChanged)
  Q_PROPERTY(double value READ value NOTIFY changed)
  Q_PROPERTY(QString text READ text NOTIFY changed)
  Q_PROPERTY(QString unit READ unit NOTIFY keyChanged)
  Q_PROPERTY(double minimum READ minimum NOTIFY keyChanged)
  Q_PROPERTY(double maximum READ maximum NOTIFY keyChanged)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status NOTIFY changed)
  Q_PROPERTY(QString errorString READ errorString NOTIFY changed)
 public:
  explicit SignalValue(QObject* parent = nullptr);
  [[nodiscard]] QString key() const { return m_key; }
  void setKey(const QString& key);
  [[nodiscard]] double staleAfterMs() const noexcept { return static_cast<double>(m_staleAfterNs) / 1e6; }
  void setStaleAfterMs(double milliseconds);
  [[nodiscard]] double value() const noexcept { return m_value; }
  [[nodiscard]] QString text() const { return m_text; }
  [[nodiscard]] QString unit() const;
  [[nodiscard]] double minimum() const;
  [[nodiscard]] double maximum() const;
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  /// Reads the table now (also on every display tick).
  Q_INVOKABLE void refresh();
 Q_SIGNALS:
  void keyChanged();
  void changed();

 private:
  QString m_key;
  std::optional<sig::SignalIndex> m_index;
  std::int64_t m_staleAfterNs{2'000'000'000};
  double m_value{};
  QString m_text{QStringLiteral("--")};
  ModelStatus::Value m_status{ModelStatus::NotConnected};
  QString m_error;
};

/// The dashboard file's dials and tiles (--dashboard FILE). Status Error with the file's
/// error when it is refused; the HMI then runs with the defaults.
class DashboardSettings : public QObject {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QString voltageKey READ voltageKey CONSTANT)
  Q_PROPERTY(QString currentKey READ currentKey CONSTANT)
  Q_PROPERTY(QString powerKey READ powerKey CONSTANT)
  /// [minimum, maximum] of each dial (the file's, else 0..1000 V, -400..400 A, -300..300 kW)
  Q_PROPERTY(QVariantList voltageRange READ voltageRange CONSTANT)
  Q_PROPERTY(QVariantList currentRange READ currentRange CONSTANT)
  Q_PROPERTY(QVariantList powerRange READ powerRange CONSTANT)
  Q_PROPERTY(QString socKey READ socKey CONSTANT)
  Q_PROPERTY(QString sohKey READ sohKey CONSTANT)
  Q_PROPERTY(QString chargerKey READ chargerKey CONSTANT)
  Q_PROPERTY(QStringList statusKeys READ statusKeys CONSTANT)
  Q_PROPERTY(double staleAfterMs READ staleAfterMs CONSTANT)
  Q_PROPERTY(openvcu::hmi::ModelStatus::Value status READ status CONSTANT)
  Q_PROPERTY(QString errorString READ errorString CONSTANT)
 public:
  explicit DashboardSettings(QObject* parent = nullptr);
  [[nodiscard]] QString voltageKey() const { return QString::fromStdString(m_config.voltageKey); }
  [[nodiscard]] QString currentKey() const { return QString::fromStdString(m_config.currentKey); }
  [[nodiscard]] QString powerKey() const { return QString::fromStdString(m_config.powerKey); }
  [[nodiscard]] QVariantList voltageRange() const { return range(m_config.voltageRange); }
  [[nodiscard]] QVariantList currentRange() const { return range(m_config.currentRange); }
  [[nodiscard]] QVariantList powerRange() const { return range(m_config.powerRange); }
  [[nodiscard]] QString socKey() const { return QString::fromStdString(m_config.socKey); }
  [[nodiscard]] QString sohKey() const { return QString::fromStdString(m_config.sohKey); }
  [[nodiscard]] QString chargerKey() const { return QString::fromStdString(m_config.chargerKey); }
  [[nodiscard]] QStringList statusKeys() const {
    QStringList keys;
    for (const std::string& key : m_config.statusKeys) keys << QString::fromStdString(key);
    return keys;
  }
  [[nodiscard]] double staleAfterMs() const noexcept { return static_cast<double>(m_config.staleAfterMs); }
  [[nodiscard]] ModelStatus::Value status() const noexcept { return m_status; }
  [[nodiscard]] QString errorString() const { return m_error; }
  [[nodiscard]] const config::DashboardConfig& config() const noexcept { return m_config; }

 private:
  static QVariantList range(const config::DialRange& dial) { return {dial.minimum, dial.maximum}; }
  config::DashboardConfig m_config;
  ModelStatus::Value m_status{ModelStatus::Ready};
  QString m_error;
};

/// A list of signals with their current text, status and tone. Either `keys` (the
/// vehicle status table: labels are the keys' last components) or `dashboard: true` (the
/// tiles of the dashboard file). Rows change only when their text or status changes.
class SignalListModel : public StatusListModel {
  Q_OBJECT
  QML_ELEMENT
  Q_PROPERTY(QStringList keys READ keys WRITE setKeys NOTIFY keysChanged)
  Q_PROPERTY(bool dashboard READ dashboard WRITE setDashboard NOTIFY keysChanged)
 public:
  enum Role { KeyRole = Qt::UserRole + 1, LabelRole, TextRole, StatusRole, ToneRole, DetailRole };
  explicit SignalListModel(QObject* parent = nullptr);
  [[nodiscard]] int rowCount(const QModelIndex& parent = {}) const override;
  [[nodiscard]] QVariant data(const QModelIndex& index, int role) const override;
  [[nodiscard]] QHash<int, QByteArray> roleNames() const override;
  [[nodiscard]] QStringList keys() const;
  void setKeys(const QStringList& keys);
  [[nodiscard]] bool dashboard() const noexcept { return m_dashboard; }
  void setDashboard(bool dashboard);
  /// Reads the table now (also on every display tick).
  Q_INVOKABLE void refresh();
 Q_SIGNALS:
  void keysChanged();

 private:
  struct Row {
    config::DashboardItem item;
    std::optional<sig::SignalIndex> index;
    QString text{QStringLiteral("--")};
    ValueStatus status{ValueStatus::NotConnected};
    TextTone tone{TextTone::Neutral};
  };
  void setRows(std::vector<config::DashboardItem> items);
  std::vector<Row> m_rows;
  bool m_dashboard{};
  std::int64_t m_staleAfterNs{2'000'000'000};
};

}  // namespace openvcu::hmi
