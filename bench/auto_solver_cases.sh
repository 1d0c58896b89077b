# The cases of bench/auto_solver.sh and bench/reuse_rule.sh: backward Euler where the step
# matrix's solver and its reuse matter (sourced; defines the array `cases`, "name|arguments").
# shellcheck disable=SC2034  # used by the scripts that source this file
cube=(demos/cube_gravity.toml --set frames.duration=0.5 --set integrator.kind=backward_euler)
stiff=("${cube[@]}" --set zones.global=false)
cases=(
  "unh900_8ms|${stiff[*]} --set material.model=unh --set material.lambda=900 --set integrator.dt=0.008"
  "unh9900_8ms|${stiff[*]} --set material.model=unh --set material.lambda=9900 --set integrator.dt=0.008"
  "unh9900_33ms|${stiff[*]} --set material.model=unh --set material.lambda=9900 --set integrator.dt=0.033"
  "snh9900_8ms|${stiff[*]} --set material.model=snh --set material.lambda=9900 --set integrator.dt=0.008"
  "cnh_8ms|${cube[*]} --set integrator.dt=0.008"
  "cnh_33ms|${cube[*]} --set integrator.dt=0.033"
  "twist|demos/twist.toml"
  "pinned7|demos/pinned_cube.toml --set mesh.cells=7"
  "pinned13|demos/pinned_cube.toml --set mesh.cells=13"
)
