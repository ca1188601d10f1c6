//! The parameters in which two runs differ, as short `name=value` labels: what a caption over
//! two pictures, or the head of `compare.json`, says about A and B.

use crate::params::table::{self, Param};
use crate::params::{Method, SolverParams};

/// One key whose value differs between A and B, with each side's value as text
/// ([`Param::text`]: short where that is exact, so `2e9`, not `2000000000`).
#[derive(Clone, Debug)]
pub struct Difference {
    pub param: &'static Param,
    pub a: String,
    pub b: String,
}

impl Difference {
    /// `name=value` of side A.
    pub fn label_a(&self) -> String {
        format!("{}={}", self.param.name(), self.a)
    }

    /// `name=value` of side B.
    pub fn label_b(&self) -> String {
        format!("{}={}", self.param.name(), self.b)
    }
}

/// The keys of the parameter table whose values differ, in the table's (the scene file's)
/// order. The joint sets of rock masses are not table keys and are never changed by a spec.
pub fn differences(a: &SolverParams, b: &SolverParams) -> Vec<Difference> {
    table::ALL
        .iter()
        .filter(|p| (p.get)(a) != (p.get)(b))
        .map(|p| Difference {
            param: p,
            a: p.text(a),
            b: p.text(b),
        })
        .collect()
}

/// Each side's labels: `(["method=alm"], ["method=penalty"])`.
pub fn labels(a: &SolverParams, b: &SolverParams) -> (Vec<String>, Vec<String>) {
    differences(a, b)
        .iter()
        .map(|d| (d.label_a(), d.label_b()))
        .unzip()
}

/// A method as the paper names it: "ALM (DDA-3a)", "penalty (DDA-3p)".
pub fn method_name(m: Method) -> &'static str {
    match m {
        Method::Alm => "ALM (DDA-3a)",
        Method::Penalty => "penalty (DDA-3p)",
    }
}

/// The caption of one side's picture (the viewer's pane, a half of a `render --compare`
/// frame): "A: ALM (DDA-3a)   method=alm".
pub fn caption(side: &str, params: &SolverParams, labels: &[String]) -> String {
    let mut s = format!("{side}: {}", method_name(params.method));
    if !labels.is_empty() {
        s.push_str("   ");
        s.push_str(&labels.join(", "));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Method;

    #[test]
    fn only_the_changed_keys_are_labelled_short() {
        let a = SolverParams::default();
        assert!(differences(&a, &a).is_empty());
        let mut b = a.clone();
        b.method = Method::Penalty;
        b.contact.initial_penalty = 2e9;
        b.joint.friction_angle = 20.0;
        let (la, lb) = labels(&a, &b);
        assert_eq!(
            la,
            ["method=alm", "initial_penalty=2e8", "friction_angle=35"]
        );
        assert_eq!(
            lb,
            ["method=penalty", "initial_penalty=2e9", "friction_angle=20"]
        );
        // Values that print alike when short are written in full.
        b = a.clone();
        b.contact.eps1 = 0.010_000_01;
        let (la, lb) = labels(&a, &b);
        assert_eq!(
            (la[0].as_str(), lb[0].as_str()),
            ("eps1=0.01", "eps1=1.000001e-2")
        );
    }
}
