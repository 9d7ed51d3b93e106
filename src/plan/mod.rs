//! What a stage hands an executor: the prepared inputs of one search (its parameters, frame,
//! positions in the frame and the pair's constant arrays) and the steps of a global search.
//! The stages (`search`, `contact`) write these and both executors (`gpu`, `cpu`) read them, so
//! neither executor depends on a stage.

pub mod grid;
pub(crate) mod increment;

use std::sync::Arc;

use crate::abi::search::SearchParams;
use grid::Grid;

/// The steps of one global search, in order (shader and CPU mirror of the same name).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The search tree's boxes from the positions, leaves up (`tree.wgsl`); collapsed facets
    /// get empty boxes.
    TreeRefit,
    /// Nearest facet per slave node (`nearest_facet.wgsl`: a walk of the tree pruned by the
    /// best distance, at most `WALK_VISITS` nodes; what a capped walk did not reach projected
    /// in chunks of bounded size, combined by atomic minima, ties to the lowest id).
    NearestFacet,
}

/// All steps of a global search, in order.
pub const STEPS: [Step; 2] = [Step::TreeRefit, Step::NearestFacet];

/// Input of one search in the kernels' layout: grid-local f32 nodes, active facets, slaves.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// Uniform parameters.
    pub params: SearchParams,
    /// The grid (its origin is the local frame).
    pub grid: Grid,
    /// Every model node, grid-local, w = its mass.
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
    /// A local-search increment (in the frame of the last global search) rather than a global one.
    pub local: bool,
    /// Model nodes (`nodes` is empty when the positions stay on the device).
    pub n_nodes: usize,
}
