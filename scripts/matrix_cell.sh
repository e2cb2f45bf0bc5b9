# shellcheck shell=bash
# The accuracy matrix's cell rules, in one place (sourced by accuracy_job.sh, ab_matrix.sh and
# calib_sensitivity.sh): seed 1 the Lissajous (Horizon-like) pattern on the nominal mount, even seeds
# the rosette pattern, seeds >= 2 draw both extrinsics and the Velodyne sweep phase; SCENE+handheld
# carries the scene's route by hand; the IMU's noise is LEVEL times a BMI088's datasheet densities
# (LEVEL 5 reaches gyro 1e-3 rad/s/sqrt(Hz), accelerometer 1e-2 m/s^2/sqrt(Hz), bias walk 3e-4
# m/s^3/sqrt(Hz) and a 0.05 m/s^2 accelerometer bias per axis).

# cell_pattern SEED: the solid-state LiDAR's scan pattern of a cell.
cell_pattern() {
  if [ $(($1 % 2)) -eq 0 ]; then echo rosette; else echo lissajous; fi
}

# simulate_cell MMLIO SCENE[+handheld] SEED LEVEL PEOPLE DIR: writes DIR/SCENE.bag, DIR/SCENE_gt.tum
# and DIR/SCENE_truth.yaml (SCENE without +handheld); the simulator's output in DIR/simulate.log.
simulate_cell() {
  local mmlio=$1 scene=$2 seed=$3 level=$4 people=$5 dir=$6
  local args=(--seed "$seed" --pattern "$(cell_pattern "$seed")" --people "$people")
  if [ "${scene%+handheld}" != "$scene" ]; then
    scene=${scene%+handheld}
    args+=(--handheld)
  fi
  [ "$seed" -ge 2 ] && args+=(--random-mount)
  args+=(--acc-noise "$(echo "0.002*$level" | bc -l)" --gyro-noise "$(echo "0.0002*$level" | bc -l)"
         --acc-walk "$(echo "0.00006*$level" | bc -l)" --gyro-walk "$(echo "0.000004*$level" | bc -l)"
         --acc-bias "$(echo "0.01*$level" | bc -l)")
  mkdir -p "$dir"
  "$mmlio" -q simulate --scenario "$scene" "${args[@]}" --out "$dir" > "$dir/simulate.log" 2>&1
}
