// Odometry stage: de-skew each LiDAR's scan, extract its features, judge solid-state frames by
// their edges, and merge the LiDARs' features (thinned per voxel) in the body frame.
#include <tbb/parallel_for.h>

#include "mmlio/lidar/deskew.hpp"
#include "mmlio/lidar/voxel_filter.hpp"
#include "odometry_impl.hpp"

namespace mmlio::estimator {

bool Odometry::Impl::usesSurfacePoints(const std::string& sensor) const {
  if (cfg.surface_points == SurfacePoints::kAll) return true;
  return cfg.surface_points == SurfacePoints::kSolidState && setupOf(sensor)->extrinsic.kind == LidarKind::kSolidState;
}

// The sweep's scans are moved into their de-skewed copies. with_view: also this sweep's view of
// free space (a range image per LiDAR).
Features Odometry::Impl::extract(lidar::AlignedSweep& sweep, const lidar::SweepMotion& motion, bool with_view,
                                 SweepResult* out) {
  const double end_s = toSec(sweep.end_ns - sweep.start_ns);
  edge_poor.assign(lidars.size(), 0);
  std::vector<LidarScan*> scans;
  for (auto& scan : sweep.scans)
    if (setupOf(scan.sensor)) scans.push_back(&scan);
  std::vector<lidar::FeatureCloud> clouds(scans.size());
  std::vector<LidarScan> deskewed(scans.size());
  std::vector<LidarFrameStats> stats(scans.size());
  std::vector<char> surface_points(scans.size(), 0);  // every return is matched as a plane point
  std::vector<SensorView> views(with_view ? scans.size() : 0);
  // Each LiDAR's extrinsic with the online calibration's correction, and where its de-skewed points
  // go: moved for its clock correction too.
  std::vector<Eigen::Isometry3d> T_body_sensor(scans.size()), T_placed(scans.size());
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const std::size_t lidar = indexOf(scans[i]->sensor);
    T_body_sensor[i] = calibration.extrinsic(lidar);
    T_placed[i] = calibration.clockShift(lidar, sweep_v_body, sweep_w_body) * T_body_sensor[i];
  }
  tbb::parallel_for(std::size_t(0), scans.size(), [&](std::size_t i) {
    const LidarSetup& setup = *setupOf(scans[i]->sensor);
    deskewed[i] = std::move(*scans[i]);
    lidar::deskewToEnd(deskewed[i], T_body_sensor[i], motion, end_s);
    if (!views.empty()) {
      views[i].source = static_cast<std::uint8_t>(indexOf(setup.extrinsic.name));
      views[i].T_body_sensor = T_placed[i];
      views[i].image = map::RangeImage(deskewed[i].points, cfg.dynamic.image);
    }
    // Where every return is a surface point, scan-line plane features would go unused.
    surface_points[i] = usesSurfacePoints(setup.extrinsic.name);
    lidar::FeatureConfig features = cfg.features;
    features.planes = !surface_points[i];
    clouds[i] = lidar::extractFeatures(deskewed[i], setup.extrinsic.kind, setup.num_rings, features);
    stats[i].sensor = setup.extrinsic.name;
    stats[i].points = deskewed[i].points.size();
    stats[i].edges = clouds[i].edges.size();
    stats[i].planes = surface_points[i] ? deskewed[i].points.size() : clouds[i].planes.size();
    if (setup.extrinsic.kind == LidarKind::kSolidState) {
      const lidar::BadFrameResult bad = lidar::checkSolidStateFrame(clouds[i], cfg.bad_frame);
      stats[i].bad_frame = bad.bad;
      stats[i].counted_edges = bad.counted_edges;
    }
  });

  // A frame kept for judgement is thinned on its own: should registration reject it, the other
  // LiDARs' features are then exactly those they have without it (a shared voxel would otherwise
  // carry its centroid, or go with it).
  std::vector<Point> edges, planes;
  std::vector<std::vector<Point>> judged_edges(lidars.size()), judged_planes(lidars.size());
  std::size_t n_edges = 0, n_planes = 0, n_points = 0;
  for (const LidarFrameStats& s : stats) {
    n_edges += s.edges;
    n_planes += s.planes;
    n_points += s.points;
  }
  edges.reserve(n_edges);
  planes.reserve(n_planes);
  if (cfg.keep_points) out->points_body.reserve(n_points);
  std::vector<char> dropped(scans.size(), 0);  // bad frames that leave the sweep before registration
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Eigen::Isometry3f T = T_placed[i].cast<float>();
    const auto source = static_cast<std::uint8_t>(indexOf(deskewed[i].sensor));
    auto toBody = [&T, source](const std::vector<Point>& pts, std::vector<Point>* dst) {
      for (Point p : pts) {
        p.xyz = T * p.xyz;
        p.source = source;
        dst->push_back(p);
      }
    };
    // Judged by information, an edge-poor frame stays in until registration has seen what it constrains.
    const bool keep_for_judgement = stats[i].bad_frame && cfg.bad_frame.by_information;
    if (keep_for_judgement) edge_poor[source] = 1;
    dropped[i] = stats[i].bad_frame && !keep_for_judgement;
    if (!dropped[i] && !calibration.measuresOnly(source)) {
      toBody(clouds[i].edges, keep_for_judgement ? &judged_edges[source] : &edges);
      toBody(surface_points[i] ? deskewed[i].points : clouds[i].planes,
             keep_for_judgement ? &judged_planes[source] : &planes);
    }
    if (cfg.keep_points) toBody(deskewed[i].points, &out->points_body);
  }
  out->lidars = std::move(stats);
  view.reset();
  if (!views.empty()) {
    view = std::make_shared<SweepView>();
    view->stamp_ns = sweep.end_ns;
    for (std::size_t i = 0; i < views.size(); ++i)
      if (!dropped[i] && !calibration.measuresOnly(views[i].source)) view->sensors.push_back(std::move(views[i]));
  }

  Features f;
  // A voxel shared by two LiDARs keeps its first point's source.
  auto toVec = [](const std::vector<Point>& pts, std::vector<Eigen::Vector3d>* dst, std::vector<std::uint8_t>* src) {
    dst->reserve(dst->size() + pts.size());
    src->reserve(src->size() + pts.size());
    for (const Point& p : pts) {
      dst->push_back(p.xyz.cast<double>());
      src->push_back(p.source);
    }
  };
  // The calibration's features: each LiDAR's own, evenly thinned (no other LiDAR shares their voxels).
  calibration_features = Features{};
  if (calibration.active())
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const std::size_t lidar = indexOf(deskewed[i].sensor);
      if (dropped[i] || (lidar != calibration.anchor() && !calibration.refines(lidar))) continue;
      const Eigen::Isometry3d& T = T_placed[i];
      const auto take = [&](const std::vector<Point>& pts, std::vector<Eigen::Vector3d>* dst,
                            std::vector<std::uint8_t>* src) {
        const std::size_t stride = std::max<std::size_t>(1, pts.size() / OnlineCalibration::kFeaturesPerLidar);
        for (std::size_t k = 0; k < pts.size(); k += stride) {
          dst->push_back(T * pts[k].xyz.cast<double>());
          src->push_back(static_cast<std::uint8_t>(lidar));
        }
      };
      take(clouds[i].edges, &calibration_features.edges, &calibration_features.edge_source);
      take(surface_points[i] ? deskewed[i].points : clouds[i].planes, &calibration_features.planes,
           &calibration_features.plane_source);
    }
  toVec(lidar::voxelDownsample(edges, cfg.edge_voxel_m), &f.edges, &f.edge_source);
  toVec(lidar::voxelDownsample(planes, cfg.plane_voxel_m), &f.planes, &f.plane_source);
  for (std::size_t s = 0; s < lidars.size(); ++s) {
    toVec(lidar::voxelDownsample(judged_edges[s], cfg.edge_voxel_m), &f.edges, &f.edge_source);
    toVec(lidar::voxelDownsample(judged_planes[s], cfg.plane_voxel_m), &f.planes, &f.plane_source);
  }
  return f;
}

}  // namespace mmlio::estimator
