//! Barriers derived from declared access (after kajiya's render graph): an [`Encoder`] knows
//! the current use of every resource it has seen in one command buffer, and a pass states
//! only the use it needs next. The encoder issues the transitions that takes, all in one
//! barrier, and none where a read follows a read in the same layout. No call site tracks a
//! "from" state.
//!
//! A pass that is recorded later, beside others, is a [`Step`]: its uses, then the commands
//! that run it. Independent jobs' steps recorded together ([`Encoder::record_together`]) share
//! one barrier: a GPU then waits once for all of them, not once for each (a barrier between
//! dispatches drains the whole device before the next starts).
//!
//! Every resource starts a command buffer as [`Access::Nothing`]: a render target's earlier
//! contents are discarded (each job clears and draws the pixels it reads), and buffers the
//! host wrote, or an earlier submission left ready, are visible to a new submission without a
//! barrier (the queue submission orders them).

use super::barrier::{barrier, Access, BufferTransition, ImageTransition};
use super::memory::{Buffer, Image};
use super::GpuContext;
use ash::vk::{self, Handle};
// The maps are keyed by Vulkan handles, looked up for every use of every pass: foldhash, faster
// here than the standard SipHash, whose guard against crafted keys handles do not need.
use foldhash::{HashMap, HashMapExt};

pub struct Encoder<'a> {
    ctx: &'a GpuContext,
    pub cmd: vk::CommandBuffer,
    /// By object type and handle: handles of different types may coincide.
    current: HashMap<(vk::ObjectType, u64), Access>,
    /// The uses named by the steps [`Encoder::record_together`] records, kept between its
    /// calls so that its table is not built anew, and grown, for every stage.
    named: HashMap<(vk::ObjectType, u64), Access>,
    /// Called after each stage recorded together that has a timed step, with that step's name
    /// (the first of the stage's): where a caller times stages (with_stage_laps).
    stage_lap: Option<&'a mut dyn FnMut(vk::CommandBuffer, &'static str)>,
}

impl<'a> Encoder<'a> {
    pub fn new(ctx: &'a GpuContext, cmd: vk::CommandBuffer) -> Self {
        // Room for a batch's run of slots (up to 64, several resources each) from the start.
        let room = 512;
        Self { ctx, cmd, current: HashMap::with_capacity(room), named: HashMap::with_capacity(room), stage_lap: None }
    }

    /// The same encoder, calling `lap` after each stage recorded together whose steps include
    /// a timed one, with the first such step's name: a caller writes a timestamp there to
    /// time a batch's stages (verify/batch.rs).
    pub fn with_stage_laps(self, lap: &'a mut dyn FnMut(vk::CommandBuffer, &'static str)) -> Self {
        Self { stage_lap: Some(lap), ..self }
    }

    pub fn ctx(&self) -> &'a GpuContext {
        self.ctx
    }

    /// Makes each image and buffer ready for its next use, recording one barrier for all.
    pub fn access(&mut self, images: &[(&Image, Access)], buffers: &[(&Buffer, Access)]) {
        let mut image_transitions = Vec::with_capacity(images.len());
        for &(image, to) in images {
            if let Some(from) = self.transition((vk::ObjectType::IMAGE, image.raw.as_raw()), to) {
                image_transitions.push(ImageTransition { image, from, to });
            }
        }
        let mut buffer_transitions = Vec::with_capacity(buffers.len());
        for &(buffer, to) in buffers {
            if let Some(from) = self.transition((vk::ObjectType::BUFFER, buffer.raw.as_raw()), to) {
                buffer_transitions.push(BufferTransition { buffer, from, to });
            }
        }
        if !(image_transitions.is_empty() && buffer_transitions.is_empty()) {
            barrier(self.ctx, self.cmd, &image_transitions, &buffer_transitions);
        }
    }

    /// Records steps of independent jobs: their uses behind one barrier, then each one's
    /// commands in turn. A resource named more than once (by several steps, or twice by one)
    /// must be named for one use, a read: nothing would order two writes, or a write and a
    /// read, between their commands. It takes one transition.
    pub fn record_together(&mut self, steps: Vec<Step<'_>>) {
        let named = &mut self.named;
        named.clear();
        let mut first_use = |handle: (vk::ObjectType, u64), to: Access| match named.insert(handle, to) {
            None => true,
            Some(before) => {
                assert!(before == to && to.is_read_only(), "steps recorded together use a resource, one to write it");
                false
            }
        };
        let mut images = Vec::with_capacity(steps.iter().map(|step| step.images.len()).sum());
        images.extend(
            steps
                .iter()
                .flat_map(|step| step.images.iter().copied())
                .filter(|&(image, to)| first_use((vk::ObjectType::IMAGE, image.raw.as_raw()), to)),
        );
        let mut buffers = Vec::with_capacity(steps.iter().map(|step| step.buffers.len()).sum());
        buffers.extend(
            steps
                .iter()
                .flat_map(|step| step.buffers.iter().copied())
                .filter(|&(buffer, to)| first_use((vk::ObjectType::BUFFER, buffer.raw.as_raw()), to)),
        );
        self.access(&images, &buffers);
        let lap = steps.iter().find_map(|step| step.lap);
        for step in steps {
            (step.record)(self.ctx, self.cmd);
        }
        if let (Some(stage_lap), Some(name)) = (&mut self.stage_lap, lap) {
            stage_lap(self.cmd, name);
        }
    }

    /// Records independent jobs' lists of steps stage by stage: every list's first step
    /// together ([`Encoder::record_together`]), then every list's second, and so on.
    pub fn record_in_stages(&mut self, lists: Vec<Vec<Step<'_>>>) {
        let mut lists: Vec<_> = lists.into_iter().map(Vec::into_iter).collect();
        loop {
            let stage: Vec<Step> = lists.iter_mut().filter_map(Iterator::next).collect();
            if stage.is_empty() {
                return;
            }
            self.record_together(stage);
        }
    }

    /// The use a resource moves from, or `None` when no barrier is needed: a read after the
    /// same read (same stages, same layout).
    fn transition(&mut self, handle: (vk::ObjectType, u64), to: Access) -> Option<Access> {
        let from = self.current.insert(handle, to).unwrap_or(Access::Nothing);
        (!(from == to && to.is_read_only())).then_some(from)
    }
}

/// What records a step's commands into a command buffer.
pub type RecordCommands<'a> = Box<dyn FnOnce(&GpuContext, vk::CommandBuffer) + 'a>;

/// One pass of a job as an [`Encoder`] records it: the uses it makes of images and buffers,
/// then the commands that run it, recorded once they are ready (no barrier of their own).
pub struct Step<'a> {
    pub images: Vec<(&'a Image, Access)>,
    pub buffers: Vec<(&'a Buffer, Access)>,
    pub record: RecordCommands<'a>,
    /// The pass's name in the render summary's times, where it is one that the summary times.
    pub lap: Option<&'static str>,
}

impl<'a> Step<'a> {
    pub fn new(
        images: Vec<(&'a Image, Access)>,
        buffers: Vec<(&'a Buffer, Access)>,
        record: impl FnOnce(&GpuContext, vk::CommandBuffer) + 'a,
    ) -> Self {
        Self { images, buffers, record: Box::new(record), lap: None }
    }

    /// The same step, timed under `name`.
    pub fn timed(self, name: &'static str) -> Self {
        Self { lap: Some(name), ..self }
    }
}
