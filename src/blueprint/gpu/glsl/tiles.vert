// Rectangles over the tiles where a pass has work (pipeline/tiles.py), in clip space: what a
// full-screen pass draws, less what it would spend on empty tiles.
in vec2 in_position;
out vec2 v_uv;

void main() {
    v_uv = in_position * 0.5 + 0.5;
    gl_Position = vec4(in_position, 0.0, 1.0);
}
