// Window depth <-> distance along the view axis. u_depth_range = (near, far, ortho ? 1 : 0).
uniform vec3 u_depth_range;

float eye_depth(float z) {
    float n = u_depth_range.x;
    float f = u_depth_range.y;
    if (u_depth_range.z > 0.5) {
        return n + z * (f - n);
    }
    return n * f / (f - z * (f - n));
}

// d(eye depth) / d(window depth) at eye depth d
float eye_depth_slope(float d) {
    float n = u_depth_range.x;
    float f = u_depth_range.y;
    if (u_depth_range.z > 0.5) {
        return f - n;
    }
    return d * d * (f - n) / (n * f);
}
