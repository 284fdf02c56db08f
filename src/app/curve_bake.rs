//! Baking the sky's model into the bitmap open in the curve editor, on a worker thread (the
//! window keeps drawing): `skytune bake`'s colours for that one bitmap over a span of hours,
//! handed back as one edit that undo can take back.

use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;

use crate::files::bitmap_edit::Edit;
use crate::measure::bake;
use crate::render::GpuContext;
use crate::sky::bitmap::Rgba;
use crate::sky::resolved::SkyModel;
use crate::sky::Sky;

/// What the worker sends back: the texels (x, y, colour) or why not.
type Baked = Result<Vec<(u32, u32, Rgba)>, String>;

/// A bake under way.
pub struct CurveBake {
    /// The bitmap it is for (the editor may have moved on).
    pub key: String,
    result: Receiver<Baked>,
}

impl CurveBake {
    /// Starts baking `model` into columns `from ..= to` (wrapping) of the sky's bitmap `key`,
    /// `size` texels; an error when the bitmap or the model cannot be baked.
    pub fn start(sky: &Arc<Sky>, model: &SkyModel, key: &str, size: (u32, u32), (from, to): (u32, u32), ctx: &GpuContext) -> Result<Self, String> {
        let target = bake::bake_target(sky, key).ok_or_else(|| format!("{key}: only a dome's gradients, fog_color, sun_ambient and sun_diffuse have a model's colour to bake"))?;
        let method =
            bake::method_of(model).ok_or_else(|| "choose a physical or analytic model (not bitmaps, not the reference) in the sky model panel to bake from".to_string())?;
        let (w, h) = size;
        let columns: Vec<u32> = if to >= from { (from..=to).collect() } else { (from..w).chain(0..=to).collect() };
        let (rows, weathers) = bake::bake_shape(target, h);
        let (sky, ctx) = (sky.clone(), ctx.clone());
        let (send, result) = mpsc::channel();
        std::thread::Builder::new()
            .name("curve-bake".into())
            .spawn(move || {
                let out = crate::measure::model_points::Evaluator::new(&ctx)
                    .and_then(|ev| bake::bake(&ev, &sky, method, rows, weathers))
                    .map(|baked| bake::bitmap_texels(&baked, target, w, h, &columns))
                    .map_err(|e| format!("bake failed: {e:#}"));
                let _ = send.send(out);
            })
            .map_err(|e| format!("cannot start the bake's worker: {e}"))?;
        Ok(Self { key: key.to_string(), result })
    }

    /// The edit, once the worker is done (None while it runs).
    pub fn poll(&self) -> Option<Result<Edit, String>> {
        match self.result.try_recv() {
            Ok(r) => Some(r.map(|texels| Edit::Replace { texels })),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err("the bake's worker stopped without a result".into())),
        }
    }
}
