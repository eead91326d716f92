"""What is there: the scenario (network, area, weather, engine) and its TOML form, the presets,
base stations from operators' files, the terrain and the buildings, and the weather (homogeneous
rain, rain cells, storms, rain-rate grids and radar files). Depends on nothing else in
[`rainuav.radio`][rainuav.radio] but the engines' registry (which names a scenario may give)."""
