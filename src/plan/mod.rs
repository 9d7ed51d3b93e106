//! What a stage hands an executor: the prepared inputs of one search (its parameters, the
//! frame's origin (`frame`), positions in the frame and the pair's constant arrays), the
//! increment as a list of entries (`increment`), and where a search's plan reads its positions
//! and what it leaves.
//! The stages (`search`, `contact`) write these and both executors (`gpu`, `cpu`) read them, so
//! neither executor depends on a stage.

pub mod frame;
pub(crate) mod increment;

use std::sync::Arc;

use crate::abi::search::{GpuHit, SearchParams};
use crate::abi::status::STATUS_WORDS;

/// Input of one search in the kernels' layout: f32 nodes in the frame, active facets, slaves.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Uniform parameters.
    pub params: SearchParams,
    /// The origin of the kernels' frame, model units: a node's f32 position is relative to it.
    pub frame: [f64; 3],
    /// Every model node relative to the frame, w = its mass.
    pub nodes: Vec<[f32; 4]>,
    /// Active facets, padded node ids (the pair's constant, shared).
    pub facets: Arc<[[u32; 4]]>,
    /// Slave node ids (the pair's constant, shared).
    pub slaves: Arc<[u32]>,
    /// The active facet of each leaf slot of the search tree, `NO_FACET` for an empty slot
    /// ([`crate::search::tree::leaf_order`]; the pair's constant, shared).
    pub order: Arc<[u32]>,
    /// The slaves' indices in Morton order of their positions at the start: the order the
    /// tree walks take them in, so neighbouring invocations walk the same branches (the pair's
    /// constant, shared).
    pub walk_order: Arc<[u32]>,
    /// Active facets of each model node: words 0..=n_nodes are starts within this same array,
    /// then the lists (local_search.wgsl's layout).
    pub adjacency: Arc<[u32]>,
    /// The nodes whose motion the budget measures: slaves, then master nodes not slaves.
    pub motion_nodes: Arc<[u32]>,
    /// Model nodes.
    pub n_nodes: usize,
}

impl Prepared {
    /// The motion budget's reference before the first global search: every node at its
    /// prepared position, w = 0 (a slave untracked). The first increment searches globally
    /// whatever it holds; its motion statistic is then the motion since these positions, the
    /// same on every executor.
    pub fn start_reference(&self) -> Vec<[f32; 4]> {
        self.nodes.iter().map(|n| [n[0], n[1], n[2], 0.0]).collect()
    }
}

/// Where a search's plan reads the positions of its nodes.
#[derive(Clone, Copy)]
pub(crate) enum PlanPositions<'a> {
    /// Host positions relative to the frame's origin (subtracted in f64 by the stage), one
    /// `[f32; 4]` per model node.
    Host(&'a [[f32; 4]]),
    /// The caller's GPU buffer (one `vec4<f32>` per model node, model frame, STORAGE usage),
    /// the frame's origin (model units, f32) subtracted by the kernels.
    Buffer(&'a wgpu::Buffer, [f32; 3]),
}

/// What one run of a search's plan leaves: its status words, its plan's words up to the
/// dispatch slots (the schedule's choice and the params it fitted) and, when read back, the
/// hits (one per slave; empty otherwise).
pub(crate) struct PlanRan {
    /// The status words.
    pub status: [u32; STATUS_WORDS],
    /// The plan's words `..PLAN_SLOTS`.
    pub plan: Vec<u32>,
    /// The hits, shared with the executor's copy on the CPU path.
    pub hits: Arc<Vec<GpuHit>>,
}
