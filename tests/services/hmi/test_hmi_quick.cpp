// Qt Quick Test of the real HMI screens (qml/tst_*.qml), offscreen, on the in-process
// event bus (memq://) without a signal table: the static QML modules OpenVcu.Models and
// OpenVcu.Hmi are linked in and imported with Q_IMPORT_QML_PLUGIN. Issue 10.
#include <QtQml/qqmlextensionplugin.h>
#include <QtQuickTest/quicktest.h>

#include <QQmlEngine>
#include <memory>

#include "common/stack_connection.hpp"
#include "hmi_test_support.hpp"

Q_IMPORT_QML_PLUGIN(OpenVcu_ModelsPlugin)
Q_IMPORT_QML_PLUGIN(OpenVcu_HmiPlugin)

class Setup : public QObject {
  Q_OBJECT
 public Q_SLOTS:
  void applicationAvailable() {
    openvcu::hmi::StackSettings settings = openvcu::hmi::test::memqSettings("hmi-quick");
    settings.dataFolder = std::string(OPENVCU_SOURCE_DIR) + "/tests/data/logs";  // Browse starts here (read only)
    auto opened = openvcu::hmi::StackConnection::open(settings);
    if (!opened) qFatal("%s", opened.error().toString().c_str());
    m_stack = std::move(*opened);
  }
  void qmlEngineAvailable(QQmlEngine* engine) { engine->addImportPath(QStringLiteral("qrc:/")); }
  void cleanupTestCase() { m_stack.reset(); }

 private:
  std::unique_ptr<openvcu::hmi::StackConnection> m_stack;
};

QUICK_TEST_MAIN_WITH_SETUP(hmi, Setup)

#include "test_hmi_quick.moc"
