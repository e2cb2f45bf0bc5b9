#include "mmlio/config/calib_file.hpp"

#include <fstream>

#include "mmlio/config/yaml_binder.hpp"
#include "mmlio/core/error.hpp"
#include "mmlio/io/trajectory_writer.hpp"

namespace mmlio::config {

namespace {

YAML::Node loadYamlFile(const std::string& path) {
  if (!std::ifstream(path)) throw Error("cannot open calibration file '" + path + "' (missing file?)");
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw Error(path + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
}

/// Emits `node` as block YAML indented by `indent` spaces (for metadata we do not interpret).
std::string indentedYaml(const YAML::Node& node, int indent) {
  YAML::Emitter emitter;
  emitter << node;
  std::string text = emitter.c_str();
  std::string out;
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    out += pad + text.substr(pos, eol - pos) + "\n";
    pos = eol + 1;
  }
  return out;
}

}  // namespace

Calibration readCalibration(const std::string& path) {
  const YAML::Node root = loadYamlFile(path);
  if (!root.IsMap()) throw Error(path + ": expected a map of sensor names (e.g. 'velodyne:', 'livox:')");
  Calibration sensors;
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string name = it->first.as<std::string>();
    const YAML::Node entry = it->second;
    if (!entry.IsMap() || !entry["T_imu_sensor"]) continue;  // metadata
    SensorCalibration calib;
    const std::string where = yamlLocation(path, entry["T_imu_sensor"]) + ": sensor '" + name + "': T_imu_sensor";
    decodeYaml(entry["T_imu_sensor"], where, calib.T_imu_sensor);
    if (entry["time_offset_s"])
      decodeYaml(entry["time_offset_s"],
                 yamlLocation(path, entry["time_offset_s"]) + ": sensor '" + name + "': time_offset_s",
                 calib.time_offset_s);
    sensors[name] = calib;
  }
  if (sensors.empty())
    throw Error(path + ": no sensor found (expected top-level maps like 'velodyne:' holding T_imu_sensor)");
  return sensors;
}

void writeCalibration(const std::string& path, const Calibration& sensors, const YAML::Node& extra) {
  if (extra.IsDefined() && !extra.IsNull() && !extra.IsMap())
    throw Error("writing calibration '" + path + "': extra must be a map");
  for (const auto& [name, calib] : sensors)
    validateRigidTransform(calib.T_imu_sensor.matrix(), "writing calibration '" + path + "': sensor '" + name + "'");

  io::writeFileAtomically(path, [&](std::ostream& out) {
    out << "# mmlio calibration. T_imu_sensor: 4x4 row-major, maps sensor points into the IMU frame.\n"
        << "# time_offset_s: t_imu = t_stamp + time_offset_s.\n";
    for (const auto& [name, calib] : sensors) {
      out << encodeYaml(name, 0) << ":\n";
      const std::string key = "  T_imu_sensor: ";
      out << key << encodeYaml(calib.T_imu_sensor, static_cast<int>(key.size()) + 1) << '\n';
      out << "  time_offset_s: " << encodeYaml(calib.time_offset_s, 0) << '\n';
      if (extra.IsMap() && extra[name] && extra[name].IsMap()) {
        YAML::Node more(YAML::NodeType::Map);
        for (auto it = extra[name].begin(); it != extra[name].end(); ++it) {
          const std::string k = it->first.as<std::string>();
          if (k != "T_imu_sensor" && k != "time_offset_s") more[k] = it->second;
        }
        if (more.size() > 0) out << indentedYaml(more, 2);
      }
    }
    if (extra.IsMap()) {
      YAML::Node meta(YAML::NodeType::Map);
      for (auto it = extra.begin(); it != extra.end(); ++it) {
        const std::string k = it->first.as<std::string>();
        if (sensors.count(k) && !it->second.IsMap())
          throw Error("writing calibration '" + path + "': extra key '" + k + "' clashes with the sensor of that name");
        if (!sensors.count(k)) meta[k] = it->second;
      }
      if (meta.size() > 0) out << indentedYaml(meta, 0);
    }
  });
}

}  // namespace mmlio::config
