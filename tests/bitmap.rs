//! Bitmap sampling as the NeL engine does it, checked against hand-computed values.

use skytune::sky::bitmap::{blur3, weather_gradient, ColorBitmap};

fn close(a: [f32; 4], b: [f32; 4]) {
    for i in 0..4 {
        assert!((a[i] - b[i]).abs() < 1e-5, "{a:?} != {b:?}");
    }
}

/// 4 columns (hours 0, 6, 12, 18 of a 24 h day) by 3 rows (weather 0, 0.5, 1).
fn bitmap() -> ColorBitmap {
    ColorBitmap::from_fn(4, 3, |x, y| [x as f32 * 0.1, y as f32 * 0.25, 0.5, 1.0 - x as f32 * 0.2])
}

#[test]
fn columns_sit_on_their_hours() {
    let b = bitmap();
    close(b.sample(0.0, 24.0, 0.0), [0.0, 0.0, 0.5, 1.0]);
    close(b.sample(6.0, 24.0, 0.0), [0.1, 0.0, 0.5, 0.8]);
    close(b.sample(18.0, 24.0, 0.0), [0.3, 0.0, 0.5, 0.4]);
}

#[test]
fn bilinear_between_hours() {
    // Hour 3: x = 3/24 * 4 = 0.5, halfway between columns 0 and 1.
    close(bitmap().sample(3.0, 24.0, 0.0), [0.05, 0.0, 0.5, 0.9]);
}

#[test]
fn midnight_blends_last_column_into_first() {
    // Hour 21: x = 3.5, halfway between column 3 and column 0 (wrapping).
    close(bitmap().sample(21.0, 24.0, 0.0), [0.15, 0.0, 0.5, 0.7]);
    // Hour 24 is hour 0 of the next day; negative hours wrap too.
    close(bitmap().sample(24.0, 24.0, 0.0), bitmap().sample(0.0, 24.0, 0.0));
    close(bitmap().sample(-3.0, 24.0, 0.0), bitmap().sample(21.0, 24.0, 0.0));
}

#[test]
fn hours_per_day_scales_the_time_axis() {
    // A 12-hour day: hour 3 is a quarter of the day, column 1.
    close(bitmap().sample(3.0, 12.0, 0.0), [0.1, 0.0, 0.5, 0.8]);
}

#[test]
fn weather_is_clamped_and_scaled_by_height_minus_one() {
    let b = bitmap();
    close(b.sample(0.0, 24.0, 1.0), [0.0, 0.5, 0.5, 1.0]);
    close(b.sample(0.0, 24.0, 7.0), [0.0, 0.5, 0.5, 1.0]);
    close(b.sample(0.0, 24.0, -2.0), [0.0, 0.0, 0.5, 1.0]);
    // Weather 0.25: y = 0.25 * 2 = 0.5, between rows 0 and 1.
    close(b.sample(0.0, 24.0, 0.25), [0.0, 0.125, 0.5, 1.0]);
}

#[test]
fn bilinear_in_both_axes() {
    // Hour 3 (x = 0.5), weather 0.75 (y = 1.5).
    close(bitmap().sample(3.0, 24.0, 0.75), [0.05, 0.375, 0.5, 0.9]);
}

fn gradient(value: f32) -> ColorBitmap {
    // One column (time does not matter), three texels along the dome: value, 2 value, 3 value.
    ColorBitmap::from_fn(1, 3, |_, y| [value * (y + 1) as f32, 0.0, 0.0, 1.0])
}

#[test]
fn blur_is_three_tap_box_with_clamped_edges() {
    let out = blur3(&[[0.0; 4], [3.0, 0.0, 0.0, 0.0], [6.0, 0.0, 0.0, 0.0]]);
    close(out[0], [1.0, 0.0, 0.0, 0.0]); // (0 + 0 + 3) / 3
    close(out[1], [3.0, 0.0, 0.0, 0.0]); // (0 + 3 + 6) / 3
    close(out[2], [5.0, 0.0, 0.0, 0.0]); // (3 + 6 + 6) / 3
}

#[test]
fn gradient_weather_blend_picks_two_steps() {
    let steps = [gradient(0.1), gradient(0.2), gradient(0.4)];
    // N = 3, weather 0.5: w N = 1.5 -> steps 1 and 2 at t = 0.5 -> values 0.3, 0.6, 0.9, then blur.
    let g = weather_gradient(&steps, 0.0, 24.0, 0.5);
    close(g[0], [(0.3 + 0.3 + 0.6) / 3.0, 0.0, 0.0, 1.0]);
    close(g[1], [(0.3 + 0.6 + 0.9) / 3.0, 0.0, 0.0, 1.0]);
    close(g[2], [(0.6 + 0.9 + 0.9) / 3.0, 0.0, 0.0, 1.0]);
    // Weather 1: floor(3) = 3 -> both indices clamp to the last step.
    let g = weather_gradient(&steps, 0.0, 24.0, 1.0);
    close(g[1], [0.4 * 2.0, 0.0, 0.0, 1.0]);
    // Weather 0: step 0 and step 1 at t = 0 -> step 0 alone.
    let g = weather_gradient(&steps, 0.0, 24.0, 0.0);
    close(g[1], [0.2, 0.0, 0.0, 1.0]);
    // Weather 0.2: w N = 0.6 -> steps 0 and 1 at t = 0.6.
    let g = weather_gradient(&steps, 0.0, 24.0, 0.2);
    let mid = |k: f32| 0.1 * k + (0.2 * k - 0.1 * k) * 0.6;
    close(g[1], [(mid(1.0) + mid(2.0) + mid(3.0)) / 3.0, 0.0, 0.0, 1.0]);
}

#[test]
fn gradient_reads_the_column_of_the_hour() {
    // Two columns: hour 0 is 0, hour 12 is 1; hour 6 is halfway, hour 18 halfway back (wrap).
    let b = ColorBitmap::from_fn(2, 2, |x, _| [x as f32, 0.0, 0.0, 1.0]);
    close(weather_gradient(std::slice::from_ref(&b), 6.0, 24.0, 0.0)[0], [0.5, 0.0, 0.0, 1.0]);
    close(weather_gradient(&[b], 18.0, 24.0, 0.0)[0], [0.5, 0.0, 0.0, 1.0]);
}
