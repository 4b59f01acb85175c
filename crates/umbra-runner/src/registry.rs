//! Backend ids and how to make them. Only the reference is registered so far.

use umbra_case::Backend;

/// Every backend id this build knows, in report order.
pub fn known() -> Vec<&'static str> {
    vec!["ref"]
}

/// Creates the backend `id`, or says which ids exist.
pub fn create(id: &str) -> Result<Box<dyn Backend>, String> {
    match id {
        "ref" => Ok(Box::new(umbra_ref::RefBackend)),
        other => Err(format!(
            "unknown backend {other:?}; this build has: {}",
            known().join(", ")
        )),
    }
}
