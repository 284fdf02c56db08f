//! A frame of the sky: [`Sky::evaluate`] samples every colour slot at the frame's hour and
//! weather, picks each object's version for the tier, and runs the particle emitters
//! ([`super::particle_sim`]) over the evaluated objects. It sits above both: the frame's types
//! ([`super::eval`]) and the simulation, which reads them.

use glam::Quat;

use super::bitmap::{self, Rgba};
use super::eval::*;
use super::resolved::*;

impl Sky {
    /// Evaluates the whole sky for one frame.
    pub fn evaluate(&self, input: &FrameInput) -> FrameSky {
        let (hour, hpd) = (input.hour.rem_euclid(self.hours_per_day), self.hours_per_day);
        let weather = input.weather.clamp(0.0, 1.0);
        let fog = self.fog_color.sample(hour, hpd, weather);
        let color = |c: &Color| self.color_at(c, hour, weather);
        let version_frame = |version: usize, v: &Version| -> VersionFrame {
            let mut constants = [[1.0; 4]; 4];
            for (k, c) in v.constants.iter().enumerate() {
                constants[k] = color(c);
            }
            let mut uv_offsets = [[0.0; 2]; 4];
            for (k, s) in v.stages.iter().enumerate() {
                let mut off = [0, 1].map(|i| (s.panner[i] as f64 * input.game_hours).rem_euclid(1.0) as f32);
                if let Some((b, factor)) = &s.uv_offset {
                    let c = b.sample(hour, hpd, weather);
                    off[0] += (c[0] - 0.5) * factor;
                    off[1] += (c[1] - 0.5) * factor;
                }
                uv_offsets[k] = off;
            }
            let gradient = v.gradients.as_ref().map(|g| bitmap::weather_gradient(&g.bitmaps, hour, hpd, weather));
            VersionFrame { version, diffuse: color(&v.diffuse), constants, uv_offsets, gradient }
        };

        let mut sky_model = input.sky_model.unwrap_or(self.model);
        let atmosphere = crate::atmosphere::Atmosphere::at_weather(&self.atmosphere_by_weather, weather as f64).unwrap_or(self.atmosphere);
        if sky_model.settings.analytic.turbidity_from_atmosphere {
            sky_model.settings.analytic.turbidity = atmosphere.turbidity().clamp(1.0, 10.0) as f32;
        }
        // Braun and Cohen's layers: alpha from the light factor (equations 3 and 4).
        let layer_alpha = |layer: Option<super::model::LayerKind>| -> f32 {
            match (sky_model.kind, layer) {
                (super::model::SkyModelKind::Linear, Some(kind)) => sky_model.settings.linear.layer_alpha(hour as f64, kind == super::model::LayerKind::Night) as f32,
                _ => 1.0,
            }
        };
        let objects = self
            .objects
            .iter()
            .enumerate()
            .map(|(index, o)| {
                let alpha = layer_alpha(o.layer);
                let placement = o.path.map(|p| self.path_at(p, hour));
                let in_view = if input.env_map { o.visible_in_env_map } else { o.visible_in_main_scene };
                let (versions, fallback): (Vec<(usize, &Version)>, bool) = if o.standard.stages.len() <= input.tier.stages() {
                    (vec![(0, &o.standard)], false)
                } else {
                    (o.fallback.iter().enumerate().map(|(i, v)| (i + 1, v)).collect(), true)
                };
                let tier = input.tier.stages();
                let dropped: Vec<(usize, usize)> = versions.iter().filter(|(_, v)| v.stages.len() > tier).map(|(i, v)| (*i, v.stages.len())).collect();
                let fitting: Vec<(usize, &Version)> = versions.iter().copied().filter(|(_, v)| v.stages.len() <= tier).collect();
                let versions = if !in_view {
                    Err(Hidden::NotInView)
                } else if input.disabled.iter().any(|d| d == &o.name) {
                    Err(Hidden::Toggled)
                } else if fitting.is_empty() {
                    let needs = versions.iter().map(|(_, v)| v.stages.len()).min().unwrap_or(o.standard.stages.len());
                    Err(Hidden::Tier { needs, has: tier })
                } else {
                    let mut frames: Vec<VersionFrame> = fitting.iter().map(|&(i, v)| version_frame(i, v)).collect();
                    for f in &mut frames {
                        f.diffuse[3] *= alpha;
                    }
                    let first = &frames[0];
                    let ref_alpha = ref_alpha(fitting[0].1.ref_color, first.diffuse, |k| first.constants[k]);
                    if ref_alpha < HIDDEN_ALPHA {
                        Err(Hidden::RefAlphaZero(fitting[0].1.ref_color))
                    } else {
                        Ok(frames)
                    }
                };
                ObjectFrame { index, priority: o.priority, versions, fallback, dropped, placement }
            })
            .collect();

        let stars = self.stars.as_ref().map(|s| StarsFrame { color: color(&s.color), priority: s.priority });
        let pole = self.stars.as_ref().map_or(45.0, |s| s.pole_elevation_deg);
        let axis = direction(0.0, pole);
        // One turn of the celestial sphere per day, around the pole, westward as seen from the
        // ground: world = celestial_from_world^-1 * celestial turns by -angle about the pole
        // (clockwise seen from above it), so stars rise in the east (tests/catalogue.rs).
        let celestial_from_world = Quat::from_axis_angle(axis, std::f32::consts::TAU * hour / hpd);
        let mut frame = FrameSky {
            hour,
            hours_per_day: hpd,
            game_hours: input.game_hours,
            weather,
            dt_s: input.dt_s,
            frame: input.frame,
            tier: input.tier,
            env_map: input.env_map,
            sky_model,
            atmosphere,
            fog_color: fog,
            sun_ambient: self.sun_ambient.sample(hour, hpd, weather),
            sun_diffuse: self.sun_diffuse.sample(hour, hpd, weather),
            towards_sun: self.path_at(self.sun_path, hour).0,
            celestial_from_world,
            objects,
            stars,
            glare: self.glare.as_ref().map(|g| color(&g.color)),
            particles: Default::default(),
        };
        if !self.emitters.is_empty() {
            frame.particles = super::particle_sim::simulate(self, input, &frame);
            // Lightning lifts the scene's light towards a cold white for the flash's duration.
            let f = frame.particles.flash.min(1.0);
            if f > 0.0 {
                let lift = |c: Rgba| -> Rgba { [0, 1, 2, 3].map(|i| if i == 3 { c[3] } else { (c[i] + f * 0.8 * [0.85, 0.9, 1.0][i]).min(1.0) }) };
                frame.fog_color = lift(frame.fog_color);
                frame.sun_ambient = lift(frame.sun_ambient);
                frame.sun_diffuse = lift(frame.sun_diffuse);
            }
        }
        frame
    }
}
