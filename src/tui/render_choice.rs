//! What the user chose to render with: the features, the plan they give
//! (the one the worker, exports and the inspector use) and the BVH
//! builder. Each change says what it did for the status line.

use crate::render::{Decision, Feature, Features, Plan, PlanPolicy, Session};
use crate::scene::{Builder, MAX_DEPTH};

/// The features, plan and builder the view is rendered with.
pub(crate) struct RenderChoice {
    features: Features,
    /// The plan of `features`, at the maximum depth chosen.
    plan: Plan,
    builder: Builder,
}

impl RenderChoice {
    pub(crate) fn new(plan: Plan, builder: Builder) -> RenderChoice {
        RenderChoice {
            features: plan.features,
            plan,
            builder,
        }
    }

    pub(crate) fn plan(&self) -> &Plan {
        &self.plan
    }

    pub(crate) fn builder(&self) -> Builder {
        self.builder
    }

    /// The decision the Features panel shows for `f`.
    pub(crate) fn decision(&self, f: Feature) -> Decision {
        self.plan.decision(f)
    }

    /// Turns `f` on or off for `session`'s scene; what to say, and whether
    /// the image changes.
    pub(crate) fn toggle(&mut self, f: Feature, session: &Session) -> (String, bool) {
        self.features.toggle(f);
        let plan = session
            .plan_for(self.features)
            .with_max_depth(self.plan.max_depth);
        let same = plan.same_stages(&self.plan);
        let state = if self.features.on(f) { "on" } else { "off" };
        let said = match crate::render::plan::not_needed(&session.scene, f) {
            Some(why) if plan.policy == PlanPolicy::Prune => format!(
                "{} {state}: not needed: {}, so the image does not change",
                f.name(),
                why.long()
            ),
            _ if same => format!("{} {state}: no change to the image", f.name()),
            _ => format!("{} {state}", f.name()),
        };
        self.plan = plan;
        (said, !same)
    }

    /// Changes the maximum depth by `steps`; what to say, and whether the
    /// image changes.
    pub(crate) fn change_depth(&mut self, steps: i8) -> (String, bool) {
        let depth = (self.plan.max_depth as i64 + steps as i64).clamp(0, MAX_DEPTH as i64) as u32;
        let what = if self.plan.path { "path" } else { "ray tree" };
        if depth == self.plan.max_depth {
            return (
                format!("maximum depth {depth}: the {what} cannot go further"),
                false,
            );
        }
        self.plan = self.plan.clone().with_max_depth(depth);
        (
            format!("maximum depth {depth}: bounces a {what} takes"),
            true,
        )
    }

    /// Switches to the other BVH builder; the one now chosen.
    pub(crate) fn switch_builder(&mut self) -> Builder {
        self.builder = match self.builder {
            Builder::Sah => Builder::Median,
            Builder::Median => Builder::Sah,
        };
        self.builder
    }
}
