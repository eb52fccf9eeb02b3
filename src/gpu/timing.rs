//! GPU timestamps around passes, so a render can report time per pass. Devices whose queue
//! has no timestamps report none rather than made-up numbers.

use super::GpuContext;
use crate::error::{Result, VkResultExt};
use ash::vk;
use std::sync::Arc;

pub struct Timestamps {
    ctx: Arc<GpuContext>,
    pool: Option<vk::QueryPool>,
    count: u32,
}

impl Timestamps {
    pub fn new(ctx: &Arc<GpuContext>, count: u32, name: &str) -> Result<Self> {
        let pool = match ctx.timestamp_period {
            None => None,
            Some(_) => {
                let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(count);
                // SAFETY: valid device.
                let pool = unsafe { ctx.device.create_query_pool(&info, None) }.vk(name)?;
                ctx.name_object(pool, name);
                Some(pool)
            }
        };
        Ok(Self { ctx: ctx.clone(), pool, count })
    }

    /// Timestamps it holds.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Resets the queries; record before the first `write`.
    pub fn reset(&self, cmd: vk::CommandBuffer) {
        if let Some(pool) = self.pool {
            // SAFETY: cmd is recording; the pool holds `count` queries.
            unsafe { self.ctx.device.cmd_reset_query_pool(cmd, pool, 0, self.count) };
        }
    }

    /// Records timestamp `index` once all earlier work has finished.
    pub fn write(&self, cmd: vk::CommandBuffer, index: u32) {
        if let Some(pool) = self.pool {
            // SAFETY: cmd is recording; index < count (callers use fixed indices).
            unsafe { self.ctx.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, pool, index) };
        }
    }

    /// Milliseconds between timestamp `from` and `to`, after the submission finished.
    pub fn millis_between(&self, from: u32, to: u32) -> Result<Option<f64>> {
        let (Some(pool), Some(period)) = (self.pool, self.ctx.timestamp_period) else { return Ok(None) };
        let mut ticks = [0u64; 2];
        for (slot, index) in ticks.iter_mut().zip([from, to]) {
            let mut one = [0u64; 1];
            // SAFETY: the submission that wrote the query has completed.
            unsafe {
                self.ctx.device.get_query_pool_results(
                    pool,
                    index,
                    &mut one,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
            }
            .vk("reading timestamps")?;
            *slot = one[0];
        }
        Ok(Some(ticks[1].wrapping_sub(ticks[0]) as f64 * period / 1e6))
    }
}

impl Drop for Timestamps {
    fn drop(&mut self) {
        if let Some(pool) = self.pool {
            // SAFETY: owned; the submission using it has completed.
            unsafe { self.ctx.device.destroy_query_pool(pool, None) };
        }
    }
}
