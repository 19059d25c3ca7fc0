// brdf-remap probe scene for POV-Ray 3.7 (right-handed via a negative right vector)
#version 3.7;
global_settings {{ assumed_gamma 1.0 ambient_light rgb 0 max_trace_level 5 }}
background {{ color rgb 0 }}
camera {{
  perspective
  location <{camera_x}, {camera_y}, {camera_z}>
  right -x
  up y
  sky <{up_x}, {up_y}, {up_z}>
  angle {fov}
  look_at <{target_x}, {target_y}, {target_z}>
}}
// point light: radiant intensity I (W/sr), inverse-square falloff.
// POV attenuation = 2/(1+(d/fd)^2) ~= 2 fd^2/d^2 for tiny fd, so colour = I/(2 fd^2)
light_source {{
  <{light_x}, {light_y}, {light_z}>
  color rgb {light_intensity}*500000
  fade_distance 0.001
  fade_power 2
}}
sphere {{
  <{sphere_x}, {sphere_y}, {sphere_z}>, {sphere_radius}
  {material}
}}
