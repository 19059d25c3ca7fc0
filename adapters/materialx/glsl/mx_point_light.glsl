// A point light of radiant intensity `intensity` (W/sr) falling off with the square of the distance,
// as the path tracers' point lights do. MaterialX's own point light divides by (distance + 1)^decay_rate,
// a real-time renderer's convention that keeps a light near a surface finite; the brdf-remap MaterialX
// renderer binds this implementation to MaterialX's `point_light` node instead, so that its images are
// in the same physical units as every other adapter's (the white Lambertian's calibration tests it).
void mx_point_light(LightData light, vec3 position, out lightshader result)
{
    result.direction = light.position - position;
    float distance = length(result.direction);
    result.intensity = light.color * light.intensity / pow(distance, light.decay_rate);
    result.direction /= distance;
}
