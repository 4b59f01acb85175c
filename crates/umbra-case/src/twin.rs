//! Metamorphic twins: variants of a case that must relate to it in a known way on *every*
//! backend (docs/catalogue.md §1–4 and the metamorphic list). A twin is the case with a few
//! dotted paths set, exactly like a sweep point, so it is parsed and validated like a file.
//!
//! One twin is built in: `bias-order`, the other bias-matrix order (docs/catalogue.md §1), held to
//! `legal`, so that every case on every backend shows both orders agree except at ties.

use std::collections::BTreeMap;

use serde_json::Value;

use crate::error::{CaseError, CaseErrors};
use crate::format::{BiasMatrix, Case, TwinAgree};
use crate::point::{CasePoint, parse_value, set_path};
use crate::validate::validate;

/// Name of the built-in twin.
pub use crate::format::BIAS_ORDER;

/// One twin of a case point, ready to run (or why it cannot be built).
pub struct TwinPlan {
    /// Its name.
    pub name: String,
    /// How it must relate to the case.
    pub agree: TwinAgree,
    /// The twin's point.
    pub point: Result<CasePoint, CaseErrors>,
}

/// Every twin of `point`: the built-in bias-order twin, then the case's own.
pub fn twins_of(point: &CasePoint) -> Vec<TwinPlan> {
    let other = match point.case.shadow.bias_matrix {
        BiasMatrix::BeforeDivide => "after_divide",
        BiasMatrix::AfterDivide => "before_divide",
    };
    let mut plans = vec![TwinPlan {
        name: BIAS_ORDER.into(),
        agree: TwinAgree::Legal,
        point: with_values(
            point,
            &BTreeMap::from([("shadow.bias_matrix".to_string(), Value::from(other))]),
            "the built-in bias-order twin",
        ),
    }];
    for (i, t) in point.case.expect.twins.iter().enumerate() {
        plans.push(TwinPlan {
            name: t.name.clone(),
            agree: t.agree,
            point: with_values(point, &t.set, &format!("expect.twins[{i}]")),
        });
    }
    plans
}

/// Whether `a` and `b` have the same shadow pass by construction: they differ at most in
/// `shadow.bias_matrix`, which only the lit pass's lookup reads (where the bias matrix is
/// applied to the coordinate). Conservative: any other difference, even one the shadow pass
/// would not see, says no.
pub fn same_shadow_pass(a: &Case, b: &Case) -> bool {
    let mut b = b.clone();
    b.shadow.bias_matrix = a.shadow.bias_matrix;
    *a == b
}

/// `point` with each dotted path in `set` given its value; the twin has no twins of its own.
pub fn with_values(
    point: &CasePoint,
    set: &BTreeMap<String, Value>,
    what: &str,
) -> Result<CasePoint, CaseErrors> {
    let file = &point.file;
    let mut doc = serde_json::to_value(&point.case).map_err(|e| {
        CaseError::new(
            file,
            what,
            format!("cannot serialise the case: {e}"),
            "report this as a bug",
        )
    })?;
    if let Value::Object(map) = &mut doc {
        if let Some(Value::Object(expect)) = map.get_mut("expect") {
            expect.remove("twins");
        }
    }
    for (path, v) in set {
        set_path(&mut doc, path)
            .map(|slot| *slot = v.clone())
            .map_err(|msg| {
                CaseError::new(
                    file,
                    format!("{what}.set.{path}"),
                    msg,
                    "give a dotted path into the case, such as shadow.attachments",
                )
            })?;
    }
    let context = format!("in {what}: ");
    let case = parse_value(&doc, file, &context).map_err(|mut e| {
        e.fix = format!("{} (the value comes from {what}.set)", e.fix);
        CaseErrors(vec![e])
    })?;
    validate(&case, file).map_err(|e| e.in_context(&context))?;
    let mut values = point.values.clone();
    values.extend(set.iter().map(|(p, v)| (p.clone(), v.clone())));
    Ok(CasePoint {
        file: file.clone(),
        case,
        values,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_bias_order_leaves_the_shadow_pass_alone() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases/basics/square-occluder.json");
        let point = crate::load_file(&file).expect("case").remove(0);
        let twins = twins_of(&point);
        let order = twins[0].point.as_ref().expect("the bias-order twin");
        assert_ne!(order.case, point.case);
        assert!(same_shadow_pass(&point.case, &order.case));
        let mut other = point.case.clone();
        other.shadow.bias.constant += 1e-4;
        assert!(!same_shadow_pass(&point.case, &other));
        let mut attachments = point.case.clone();
        attachments.shadow.attachments = crate::format::Attachments::WithColor;
        assert!(!same_shadow_pass(&point.case, &attachments));
    }
}
