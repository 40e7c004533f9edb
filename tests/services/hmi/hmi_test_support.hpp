#pragma once
// What the HMI tests share: the HHEA configuration on the in-process event bus (memq://)
// with an instance name of their own (no signal table exists for it), and the one
// QGuiApplication a test process needs before any model.
#include <unistd.h>

#include <QCoreApplication>
#include <QGuiApplication>
#include <string>

#include "common/stack_connection.hpp"

namespace openvcu::hmi::test {

inline const std::string HHEA_CONFIG = std::string(OPENVCU_SOURCE_DIR) + "/config/hhea/vehicle.json";

/// Settings for the HHEA configuration on memq:// with the instance "<prefix>-<pid>".
inline StackSettings memqSettings(const std::string& prefix) {
  StackSettings settings;
  settings.configPath = HHEA_CONFIG;
  settings.lcmUrl = "memq://";
  settings.instance = prefix + "-" + std::to_string(::getpid());
  return settings;
}

/// Creates the process's QGuiApplication (offscreen) once; `name` is its argv[0].
inline void ensureApplication(const char* name) {
  static int argc = 1;
  static std::string programName = name;
  static char* argv[] = {programName.data(), nullptr};
  if (!QCoreApplication::instance()) {
    qputenv("QT_QPA_PLATFORM", "offscreen");
    static QGuiApplication application(argc, argv);
  }
}

}  // namespace openvcu::hmi::test
