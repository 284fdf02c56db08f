// Test pass of the compute phase (tests/phases.rs): copies per-frame globals into a buffer, so the
// test can see that compute passes run each frame with bind group 0.
@group(1) @binding(0) var<storage, read_write> probe: array<f32, 4>;

@compute @workgroup_size(1)
fn cs_main() {
    probe[0] = globals.time.x;      // hour
    probe[1] = globals.time.z;      // weather
    probe[2] = globals.viewport.x;  // width, pixels
    probe[3] = probe[3] + 1.0;      // frames dispatched
}
