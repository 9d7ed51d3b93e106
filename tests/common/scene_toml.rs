//! A scene file built from its tables, for tests that would otherwise write the same TOML
//! blocks inline: `[run]`, `[[material]]`, `[[part]]`, `[[rigid]]`, `[[boundary]]` and
//! `[[contact]]`, each entry a table of keys the test names. The text is what `abut run` reads
//! (toml writes it), so a test of a built scene tests the scene file. Scenes whose test is about
//! the text itself (an error's line, a key misspelt) stay raw text.

use abut::scene::Scene;
use toml::{Table, Value};

/// A scene file under construction; [`SceneToml::text`] writes it, [`SceneToml::scene`] parses it.
#[derive(Clone, Debug)]
pub struct SceneToml {
    doc: Table,
}

/// One `[[section]]` entry: a table of keys.
#[derive(Clone, Debug, Default)]
pub struct Entry(Table);

/// What a scene key can hold: numbers, booleans, strings and arrays of them.
pub trait Val {
    /// The TOML value.
    fn val(self) -> Value;
}

impl Val for Value {
    fn val(self) -> Value {
        self
    }
}
impl Val for f64 {
    fn val(self) -> Value {
        Value::Float(self)
    }
}
impl Val for i32 {
    fn val(self) -> Value {
        Value::Integer(self.into())
    }
}
impl Val for usize {
    fn val(self) -> Value {
        Value::Integer(self as i64)
    }
}
impl Val for bool {
    fn val(self) -> Value {
        Value::Boolean(self)
    }
}
impl Val for &str {
    fn val(self) -> Value {
        Value::String(self.to_string())
    }
}
impl Val for String {
    fn val(self) -> Value {
        Value::String(self)
    }
}
impl<T: Val, const N: usize> Val for [T; N] {
    fn val(self) -> Value {
        Value::Array(self.into_iter().map(Val::val).collect())
    }
}
impl<T: Val> Val for Vec<T> {
    fn val(self) -> Value {
        Value::Array(self.into_iter().map(Val::val).collect())
    }
}

impl Entry {
    /// This entry with `key = value` (replacing an earlier value of the key).
    pub fn with(mut self, key: &str, value: impl Val) -> Self {
        self.0.insert(key.to_string(), value.val());
        self
    }

    /// This entry with `key = value` when `value` is given, as it is otherwise.
    pub fn with_some(self, key: &str, value: Option<impl Val>) -> Self {
        match value {
            Some(v) => self.with(key, v),
            None => self,
        }
    }
}

/// A part generated on a grid: `shape` (`bar`, `plate`, `block`, `rect`, `line`, …) with its
/// `origin`, `size` and `divisions`.
pub fn part(
    name: &str,
    shape: &str,
    origin: [f64; 3],
    size: [f64; 3],
    divisions: [usize; 3],
) -> Entry {
    Entry::default()
        .with("name", name)
        .with("shape", shape)
        .with("origin", origin)
        .with("size", size)
        .with("divisions", divisions)
}

/// A part of other keys (`points`, `sphere`, `mesh`): its name and shape, the rest by `with`.
pub fn part_of(name: &str, shape: &str) -> Entry {
    Entry::default().with("name", name).with("shape", shape)
}

/// A contact pair: the slave part's face against the master part's face.
pub fn contact(slave: &str, slave_face: &str, master: &str, master_face: &str) -> Entry {
    Entry::default()
        .with("slave", slave)
        .with("slave_face", slave_face)
        .with("master", master)
        .with("master_face", master_face)
}

/// A boundary entry on a part's face; what it does (`fix`, `load`, `displacement`, …) by `with`.
pub fn boundary(part: &str, face: &str) -> Entry {
    Entry::default().with("part", part).with("face", face)
}

/// A face fixed in the named axes (`"x"`, `"y"`, `"z"`).
pub fn fixed<const N: usize>(part: &str, face: &str, axes: [&str; N]) -> Entry {
    boundary(part, face).with("fix", axes)
}

impl SceneToml {
    /// A scene titled `title` that runs to `end_time`, with nothing in it yet.
    pub fn new(title: &str, end_time: f64) -> Self {
        let mut doc = Table::new();
        doc.insert("title".into(), title.val());
        let mut run = Table::new();
        run.insert("end_time".into(), end_time.val());
        doc.insert("run".into(), Value::Table(run));
        Self { doc }
    }

    /// This scene with `[run]`'s `key = value`.
    pub fn run(mut self, key: &str, value: impl Val) -> Self {
        self.doc["run"]
            .as_table_mut()
            .expect("[run] is a table")
            .insert(key.to_string(), value.val());
        self
    }

    /// This scene with a top-level `key = value` (`reference`).
    pub fn top(mut self, key: &str, value: impl Val) -> Self {
        self.doc.insert(key.to_string(), value.val());
        self
    }

    /// This scene with a linear elastic material.
    pub fn material(self, name: &str, young: f64, poisson: f64, density: f64) -> Self {
        let m = Entry::default()
            .with("name", name)
            .with("young", young)
            .with("poisson", poisson)
            .with("density", density);
        self.push("material", m)
    }

    /// This scene with `[[part]]` `entry`.
    pub fn part(self, entry: Entry) -> Self {
        self.push("part", entry)
    }

    /// This scene with `[[rigid]]` `entry`.
    pub fn rigid(self, entry: Entry) -> Self {
        self.push("rigid", entry)
    }

    /// This scene with `[[boundary]]` `entry`.
    pub fn boundary(self, entry: Entry) -> Self {
        self.push("boundary", entry)
    }

    /// This scene with `[[contact]]` `entry`.
    pub fn contact(self, entry: Entry) -> Self {
        self.push("contact", entry)
    }

    /// This scene with `key = value` set in entry `index` of `[[section]]` (to vary one key of a
    /// scene a function built).
    pub fn set_in(mut self, section: &str, index: usize, key: &str, value: impl Val) -> Self {
        let entry = self.doc[section]
            .as_array_mut()
            .and_then(|a| a.get_mut(index))
            .and_then(Value::as_table_mut)
            .unwrap_or_else(|| panic!("no [[{section}]] entry {index}"));
        entry.insert(key.to_string(), value.val());
        self
    }

    fn push(mut self, section: &str, entry: Entry) -> Self {
        self.doc
            .entry(section)
            .or_insert_with(|| Value::Array(Vec::new()))
            .as_array_mut()
            .expect("a [[section]] is an array")
            .push(Value::Table(entry.0));
        self
    }

    /// The scene file's text.
    pub fn text(&self) -> String {
        toml::to_string(&self.doc).expect("a table of plain values writes")
    }

    /// The scene, parsed from [`SceneToml::text`] (a test's scene that does not parse fails the
    /// test, with the text).
    pub fn scene(&self) -> Scene {
        let text = self.text();
        Scene::parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }
}

/// Writes the deck `text` as `name` in this test binary's own directory and reads it as a scene
/// (`Scene::load`: errors name the file and line).
pub fn deck(name: &str, text: &str) -> abut::Result<Scene> {
    let dir = std::env::temp_dir().join(format!("abut-decks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    Scene::load(&path)
}

/// A unit point mass at `height` above a rigid 1 × 1 plate under a gravity of 1000 (downwards),
/// on an undamped penalty spring of stiffness `k`, searched within 0.5, for `end` at the fixed
/// increment `dt`.
pub fn mass_on_spring(title: &str, k: f64, height: f64, dt: f64, end: f64) -> SceneToml {
    SceneToml::new(title, end)
        .run("dt", dt)
        .run("gravity", [0.0, 0.0, -1000.0])
        .part(part("plate", "plate", [0.0; 3], [1.0, 1.0, 0.0], [2, 2, 0]))
        .part(
            part_of("ball", "points")
                .with("points", [[0.4, 0.6, height]])
                .with("mass", 1.0)
                .with("velocity", [0.0, 0.0, 0.0]),
        )
        .contact(
            contact("ball", "all", "plate", "z+")
                .with("stiffness", k)
                .with("damping", 0.0)
                .with("search_radius", 0.5),
        )
}
