//! Contact pairs: a slave node set against a master surface.

use super::{NodeSetId, SurfaceId};
use crate::error::{Error, Result};

/// A contact pair: the nodes of `slave` against the facets of `master`.
#[derive(Clone, Debug, PartialEq)]
pub struct Pair {
    /// The slave node set.
    pub slave: NodeSetId,
    /// The master surface.
    pub master: SurfaceId,
    /// Search radius (model units): a slave node farther than this from every master facet has
    /// no contact partner. `None` takes one mean facet size of the master surface.
    pub search_radius: Option<f64>,
}

impl Pair {
    /// A pair of `slave` nodes against the `master` surface, default settings.
    pub fn new(slave: NodeSetId, master: SurfaceId) -> Self {
        Self {
            slave,
            master,
            search_radius: None,
        }
    }

    /// Sets the search radius (model units, finite and positive).
    pub fn search_radius(mut self, radius: f64) -> Self {
        self.search_radius = Some(radius);
        self
    }

    pub(crate) fn validate(&self) -> Result<()> {
        if let Some(r) = self.search_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::BadParameter {
                    name: "search_radius",
                    value: r.to_string(),
                    expected: "must be finite and positive",
                });
            }
        }
        Ok(())
    }
}
