//! The parameters only one part rule reads, each rule's in its own type with its defaults and its checks
//! ([`super::Params`] holds one of each; the JSON keeps them flat, [`super::wire`]).

/// The merge tree's ([`super::PartRule::Tree`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TreeParams {
    /// A coarse mesh for the part decisions ([`crate::parts::coarse_mesh`]): with at least twice this many
    /// vertices ([`crate::parts::hierarchy::COARSE_FACTOR`]), the tree, the AECM runs and the part rule's
    /// decisions run on about this many well-spread vertices with their own triangles, and only the last AECM on
    /// all vertices, from the coarse fit's parts; 0 decides on all vertices. With fewer than 20 poses the coarse
    /// mesh is larger, as many vertex-poses as this many vertices in 20 poses
    /// ([`crate::parts::hierarchy::coarse_target`]). Default 8000.
    pub coarse_vertices: usize,
}

impl Default for TreeParams {
    fn default() -> Self {
        TreeParams { coarse_vertices: 8000 }
    }
}

impl TreeParams {
    pub(super) fn problems(&self, bad: &mut dyn FnMut(&'static str, String)) {
        if self.coarse_vertices > 0 && self.coarse_vertices < 500 {
            bad(
                "coarseVertices",
                format!("= {} must be 0 (decide on all vertices) or at least 500 (try 8000)", self.coarse_vertices),
            );
        }
    }
}

/// The scale-free rule's two ratios ([`crate::parts::distinct`]), both dimensionless: read by
/// [`super::PartRule::Distinct`] after Algorithm 1 and by [`super::PartRule::Tree`] on its merge tree (the two
/// rules judge parts the same way; they differ in where the parts come from).
#[derive(Debug, Clone, PartialEq)]
pub struct DistinctParams {
    /// Two adjacent parts stay apart only if moving both by one rigid motion raises the squared error of the
    /// smaller one, per vertex, to at least this many times a typical part's variance; and (with
    /// [`super::PartRule::Distinct`]) a refinement split is kept only if it lowers the variance this many times.
    /// Default 4.
    pub distinct_ratio: f64,
    /// A part whose motion is a fixed in-between of two neighbours' motions to within this fraction of their
    /// relative rotation is flesh, not a part ([`crate::parts::distinct::blend_ratio`]). Default 0.1.
    pub blend_ratio: f64,
}

impl Default for DistinctParams {
    fn default() -> Self {
        DistinctParams { distinct_ratio: 4.0, blend_ratio: 0.1 }
    }
}

impl DistinctParams {
    pub(super) fn problems(&self, bad: &mut dyn FnMut(&'static str, String)) {
        if !(self.distinct_ratio > 0.0 && self.distinct_ratio.is_finite()) {
            bad("distinctRatio", format!("= {} must be a positive number (try 4)", super::shown(self.distinct_ratio)));
        }
        if !(0.0..1.0).contains(&self.blend_ratio) {
            bad(
                "blendRatio",
                format!("= {} must be in [0, 1) (try 0.1; 0 keeps every part)", super::shown(self.blend_ratio)),
            );
        }
    }
}

/// The paper's part rule ([`super::PartRule::Threshold`]): absolute variances, in unit-box units², so it
/// depends on the shape's size.
#[derive(Debug, Clone, PartialEq)]
pub struct ThresholdParams {
    /// Algorithm 1 step 5: stop splitting a part when its mean variance err falls below this. Default 1e-5.
    pub refine_threshold: f64,
    /// After the refinement, adjacent parts that one rigid component explains with a mean variance below
    /// `merge_ratio * refine_threshold` are merged (0 turns the merge off). Default 0.25.
    pub merge_ratio: f64,
}

impl Default for ThresholdParams {
    fn default() -> Self {
        ThresholdParams { refine_threshold: 1e-5, merge_ratio: 0.25 }
    }
}

impl ThresholdParams {
    pub(super) fn problems(&self, bad: &mut dyn FnMut(&'static str, String)) {
        if !(self.refine_threshold >= 0.0 && self.refine_threshold.is_finite()) {
            bad("refineThreshold", format!("= {} must be >= 0", super::shown(self.refine_threshold)));
        }
        if !(0.0..=1.0).contains(&self.merge_ratio) {
            bad("mergeRatio", format!("= {} must be in [0, 1]", super::shown(self.merge_ratio)));
        }
    }
}

/// Algorithm 1's ([`super::PartRule::Distinct`], [`super::PartRule::Threshold`], the refinement off, and the
/// step-by-step lesson): the coarse k-means++ start and the refinement of each coarse part.
#[derive(Debug, Clone, PartialEq)]
pub struct Algorithm1Params {
    /// Number of coarse parts m of the first AECM (Algorithm 1's input). Default 11.
    pub parts: usize,
    /// Most sub-parts tried per coarse part in the refinement. Default 6.
    pub max_subparts: usize,
    /// A sub-part must lower err by at least this fraction to be kept (makes "stops decreasing" robust).
    /// Default 0.1.
    pub refine_min_gain: f64,
    /// Iteration cap of each small AECM run inside the refinement. Default 60.
    pub refine_max_iter: usize,
    /// Multi-resolution ([`crate::parts::multires`]): with at least 3 times this many vertices
    /// ([`crate::parts::hierarchy::SUBSET_FACTOR`]), the coarse and refinement stages run on about this many
    /// well-spread vertices and only the final AECM on all of them; 0 runs every stage on all vertices (the full
    /// hierarchy). Only with `refine`. Default 2000.
    pub subset_vertices: usize,
    /// [`super::PartRule::Threshold`]'s absolute thresholds.
    pub threshold: ThresholdParams,
}

impl Default for Algorithm1Params {
    fn default() -> Self {
        Algorithm1Params {
            parts: 11,
            max_subparts: 6,
            refine_min_gain: 0.1,
            refine_max_iter: 60,
            subset_vertices: 2000,
            threshold: ThresholdParams::default(),
        }
    }
}

impl Algorithm1Params {
    pub(super) fn problems(&self, bad: &mut dyn FnMut(&'static str, String)) {
        if self.parts == 0 {
            bad("parts", format!("= {} must be {}", self.parts, super::ALLOWED_PARTS));
        } else if self.parts > 512 {
            bad("parts", format!("= {} is too large: it must be {}", self.parts, super::ALLOWED_PARTS));
        }
        self.threshold.problems(bad);
        if self.max_subparts == 0 || self.max_subparts > 64 {
            bad("maxSubparts", format!("= {} must be between 1 and 64", self.max_subparts));
        }
        if !(0.0..1.0).contains(&self.refine_min_gain) {
            bad("refineMinGain", format!("= {} must be in [0, 1)", super::shown(self.refine_min_gain)));
        }
        if self.subset_vertices > 0 && self.subset_vertices < 64 {
            bad(
                "subsetVertices",
                format!("= {} must be 0 (every stage on all vertices) or at least 64 (try 2000)", self.subset_vertices),
            );
        }
        if self.refine_max_iter == 0 {
            bad("refineMaxIter", "= 0 must be at least 1".into());
        }
    }
}
