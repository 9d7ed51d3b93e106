//! Handles, statuses and the guard every C entry point runs its body in.
//!
//! A handle the C side holds is not a pointer to memory: it is a key into a table of live
//! objects, never reused. A freed or never-made handle, or one of the wrong kind, is found
//! missing from the table and named in an error (`ABUT_STATUS_BAD_HANDLE`), not dereferenced.
//! Each object sits behind its own lock, so calls on one handle from several threads take
//! turns while calls on different handles run at once. A panic inside a call is caught at the
//! boundary, reported as `ABUT_STATUS_PANIC`, and leaves its handle refusing further calls
//! (its state may be half-changed) until it is freed.

use super::types::AbutStatus;
use crate::error::Error;
use crate::{Contact, Device, Model};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// What a handle holds.
pub(crate) enum Object {
    Device(Device),
    Model(Box<Model>),
    Contact(Box<Contact>),
}

impl Object {
    fn kind(&self) -> &'static str {
        match self {
            Object::Device(_) => "device",
            Object::Model(_) => "model",
            Object::Contact(_) => "contact",
        }
    }
}

/// One live handle: its object, its last error, and whether a panic broke it.
struct Entry {
    kind: &'static str,
    object: Mutex<Object>,
    error: Mutex<String>,
    broken: Mutex<Option<String>>,
}

/// The live handles by key.
static LIVE: Mutex<BTreeMap<usize, Arc<Entry>>> = Mutex::new(BTreeMap::new());

/// The next key (keys are never reused, so a freed handle stays invalid).
static NEXT: AtomicUsize = AtomicUsize::new(1);

thread_local! {
    /// The last error on this thread, whatever handle (or none) it came from.
    static LAST: RefCell<String> = const { RefCell::new(String::new()) };
}

/// A failed call: its status and the message naming the item at fault.
#[derive(Debug)]
pub(crate) struct Fail {
    pub status: AbutStatus,
    pub message: String,
}

impl Fail {
    pub fn new(status: AbutStatus, message: impl Into<String>) -> Self {
        Self {
            status,
            message: message.into(),
        }
    }
}

impl From<Error> for Fail {
    fn from(e: Error) -> Self {
        use crate::error::ErrorKind as K;
        let status = match e.kind() {
            K::Length => AbutStatus::Length,
            K::OutOfRange => AbutStatus::OutOfRange,
            K::BadValue => AbutStatus::BadValue,
            K::Geometry => AbutStatus::Geometry,
            K::Device => AbutStatus::Device,
            K::Contact => AbutStatus::Contact,
            K::Io => AbutStatus::Io,
        };
        Fail::new(status, e.to_string())
    }
}

/// The result of a call's body.
pub(crate) type Outcome = std::result::Result<(), Fail>;

/// Records `fail` of C entry point `call` as this thread's last error (and `entry`'s), its
/// message led by the call's name, and returns its status.
fn record_in(call: &str, mut fail: Fail, entry: Option<&Entry>) -> AbutStatus {
    if !fail.message.starts_with(call) {
        fail.message = format!("{call}: {}", fail.message);
    }
    record(fail, entry)
}

/// Records `fail` as this thread's last error (and `entry`'s) and returns its status.
fn record(fail: Fail, entry: Option<&Entry>) -> AbutStatus {
    if let Some(e) = entry {
        *lock(&e.error) = fail.message.clone();
    }
    LAST.with(|l| *l.borrow_mut() = fail.message);
    fail.status
}

/// Locks `m`, taking the data of a lock a caught panic poisoned (the entry's `broken` flag,
/// not the lock, says whether its object may be used).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The message of a panic's payload.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "(no message)".into())
}

/// Runs `body` for C entry point `call`, catching a panic: the status to return.
pub(crate) fn guard(call: &str, body: impl FnOnce() -> Outcome) -> AbutStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => AbutStatus::Ok,
        Ok(Err(f)) => record_in(call, f, None),
        Err(p) => record(
            Fail::new(
                AbutStatus::Panic,
                format!("{call}: internal error (panic): {}", panic_message(&*p)),
            ),
            None,
        ),
    }
}

/// Registers `object` and returns its handle.
pub(crate) fn register(object: Object) -> usize {
    let key = NEXT.fetch_add(1, Ordering::Relaxed);
    let entry = Arc::new(Entry {
        kind: object.kind(),
        object: Mutex::new(object),
        error: Mutex::new(String::new()),
        broken: Mutex::new(None),
    });
    lock(&LIVE).insert(key, entry);
    key
}

/// The live entry of `handle`, or the error naming it.
fn find(handle: usize, call: &str, kind: &str) -> Result<Arc<Entry>, Fail> {
    if handle == 0 {
        return Err(Fail::new(
            AbutStatus::NullPointer,
            format!("{call}: the {kind} handle is null"),
        ));
    }
    lock(&LIVE).get(&handle).cloned().ok_or_else(|| {
        Fail::new(
            AbutStatus::BadHandle,
            format!(
                "{call}: {kind} handle {handle:#x} is not live (already freed, or never made by \
                 abut)"
            ),
        )
    })
}

/// Runs `body` on the object of `handle` (a `kind`: "device", "model" or "contact") for C
/// entry point `call`: the handle checked, its lock held, a panic caught; a failure's message
/// is kept as the handle's last error and the thread's.
pub(crate) fn with_object(
    handle: usize,
    call: &str,
    kind: &'static str,
    body: impl FnOnce(&mut Object) -> Outcome,
) -> AbutStatus {
    let entry = match find(handle, call, kind) {
        Ok(e) => e,
        Err(f) => return record(f, None),
    };
    if let Some(why) = lock(&entry.broken).clone() {
        let f = Fail::new(
            AbutStatus::Panic,
            format!("{call}: this {kind} handle is unusable since {why}; free it"),
        );
        return record(f, Some(&entry));
    }
    if entry.kind != kind {
        let f = Fail::new(
            AbutStatus::BadHandle,
            format!(
                "{call}: handle {handle:#x} is a {}, not a {kind}",
                entry.kind
            ),
        );
        return record(f, Some(&entry));
    }
    let mut object = lock(&entry.object);
    let outcome = catch_unwind(AssertUnwindSafe(|| body(&mut object)));
    drop(object);
    match outcome {
        Ok(Ok(())) => AbutStatus::Ok,
        Ok(Err(f)) => record_in(call, f, Some(&entry)),
        Err(p) => {
            let what = format!(
                "an internal error (panic) in {call}: {}",
                panic_message(&*p)
            );
            *lock(&entry.broken) = Some(what.clone());
            record(Fail::new(AbutStatus::Panic, what), Some(&entry))
        }
    }
}

/// [`with_object`] on a device handle.
pub(crate) fn with_device(
    handle: usize,
    call: &str,
    body: impl FnOnce(&mut Device) -> Outcome,
) -> AbutStatus {
    with_object(handle, call, "device", |o| match o {
        Object::Device(d) => body(d),
        other => Err(kind_mismatch(call, other.kind(), "device")),
    })
}

/// [`with_object`] on a model handle.
pub(crate) fn with_model(
    handle: usize,
    call: &str,
    body: impl FnOnce(&mut Model) -> Outcome,
) -> AbutStatus {
    with_object(handle, call, "model", |o| match o {
        Object::Model(m) => body(m),
        other => Err(kind_mismatch(call, other.kind(), "model")),
    })
}

/// [`with_object`] on a contact handle.
pub(crate) fn with_contact(
    handle: usize,
    call: &str,
    body: impl FnOnce(&mut Contact) -> Outcome,
) -> AbutStatus {
    with_object(handle, call, "contact", |o| match o {
        Object::Contact(c) => body(c),
        other => Err(kind_mismatch(call, other.kind(), "contact")),
    })
}

fn kind_mismatch(call: &str, actual: &str, kind: &str) -> Fail {
    Fail::new(
        AbutStatus::BadHandle,
        format!("{call}: the handle is a {actual}, not a {kind}"),
    )
}

/// Runs `body` on two handles' objects (a device and a model, both borrowed) for `call`.
pub(crate) fn with_device_and_model(
    device: usize,
    model: usize,
    call: &str,
    body: impl FnOnce(&Device, &Model) -> Outcome,
) -> AbutStatus {
    with_device(device, call, |d| {
        let mut inner = Ok(());
        let s = with_model(model, call, |m| {
            inner = body(d, m);
            Ok(())
        });
        if s != AbutStatus::Ok {
            let message = LAST.with(|l| l.borrow().clone());
            return Err(Fail::new(s, message));
        }
        inner
    })
}

/// Frees `handle` (of `kind`) for C entry point `call`: a null handle is no error (as `free`);
/// a handle not live, or of another kind, is.
pub(crate) fn release(handle: usize, call: &str, kind: &'static str) -> AbutStatus {
    guard(call, || {
        if handle == 0 {
            return Ok(());
        }
        let entry = find(handle, call, kind)?;
        let actual = entry.kind;
        if actual != kind {
            return Err(Fail::new(
                AbutStatus::BadHandle,
                format!("{call}: handle {handle:#x} is a {actual}, not a {kind}"),
            ));
        }
        lock(&LIVE).remove(&handle);
        Ok(())
    })
}

/// The last error message of `handle` (any kind), or the thread's last with `handle` = 0.
pub(crate) fn last_error(handle: usize, call: &str) -> Result<String, Fail> {
    if handle == 0 {
        return Ok(LAST.with(|l| l.borrow().clone()));
    }
    let entry = find(handle, call, "abut")?;
    let message = lock(&entry.error).clone();
    Ok(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_is_caught_named_and_breaks_only_its_handle() {
        let h = register(Object::Model(Box::new(Model::new_3d())));
        let other = register(Object::Model(Box::new(Model::new_3d())));
        let s = with_object(h, "abut_test_call", "model", |_| panic!("on purpose"));
        assert_eq!(s, AbutStatus::Panic);
        let msg = last_error(h, "t").unwrap();
        assert!(
            msg.contains("abut_test_call") && msg.contains("on purpose"),
            "{msg}"
        );
        assert_eq!(LAST.with(|l| l.borrow().clone()), msg);
        let again = with_object(h, "abut_next", "model", |_| Ok(()));
        assert_eq!(again, AbutStatus::Panic);
        assert!(last_error(h, "t").unwrap().contains("unusable"));
        assert_eq!(
            with_object(other, "abut_next", "model", |_| Ok(())),
            AbutStatus::Ok
        );
        assert_eq!(release(h, "free", "model"), AbutStatus::Ok);
        assert_eq!(release(other, "free", "model"), AbutStatus::Ok);
        assert_eq!(
            guard("abut_guarded", || panic!("{}", String::from("owned"))),
            AbutStatus::Panic
        );
        assert!(LAST.with(|l| l.borrow().contains("owned")));
    }

    #[test]
    fn freed_wrong_kind_and_null_handles_are_named() {
        let h = register(Object::Model(Box::new(Model::new_3d())));
        assert_eq!(
            with_object(h, "abut_x", "contact", |_| Ok(())),
            AbutStatus::BadHandle
        );
        assert!(last_error(h, "t")
            .unwrap()
            .contains("is a model, not a contact"));
        assert_eq!(
            release(h, "abut_contact_free", "contact"),
            AbutStatus::BadHandle
        );
        assert_eq!(release(h, "abut_model_free", "model"), AbutStatus::Ok);
        assert_eq!(
            with_object(h, "abut_y", "model", |_| Ok(())),
            AbutStatus::BadHandle
        );
        assert!(LAST.with(|l| l.borrow().contains("not live")));
        assert_eq!(
            release(h, "abut_model_free", "model"),
            AbutStatus::BadHandle
        );
        assert_eq!(
            with_object(0, "abut_z", "model", |_| Ok(())),
            AbutStatus::NullPointer
        );
        assert_eq!(release(0, "abut_model_free", "model"), AbutStatus::Ok);
    }
}
