//! The live view's HTTP server: axum on a single-threaded tokio runtime of its own thread, so
//! the replay's thread is never held by a browser.
//!
//! - `GET /`: the page (`page.html`, self-contained: inline script and styles, no external
//!   resource).
//! - `GET /events`: server-sent events, one `update` every [`TICK`]: the first carries the
//!   `hello` (names, references, rule) and the whole history, later ones what is new
//!   ([`aeroident_pipelines::live::LiveState::update`]); after the final verdicts, one `end`
//!   event, and the stream closes.
//! - `GET /latest`: the latest sample's time and the feed's counts as JSON (for a script
//!   measuring how far the view lags the feed).

use aeroident_pipelines::live::{Cursor, SharedLive};
use axum::Router;
use axum::extract::State;
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse};
use axum::routing::get;
use std::convert::Infallible;
use std::net::SocketAddr;
use std::time::Duration;

/// How often a client gets an update (10 Hz).
pub const TICK: Duration = Duration::from_millis(100);

const PAGE: &str = include_str!("page.html");

/// Binds `addr` and serves the view of `shared` on a thread of its own; returns the bound
/// address (the port chosen when `addr`'s is 0).
///
/// # Errors
/// The address cannot be bound, or the thread or runtime cannot start.
pub fn start(addr: SocketAddr, shared: SharedLive) -> anyhow::Result<SocketAddr> {
    let listener = std::net::TcpListener::bind(addr)?;
    listener.set_nonblocking(true)?;
    let bound = listener.local_addr()?;
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    std::thread::Builder::new().name("live-view".into()).spawn(move || {
        runtime.block_on(async move {
            let app = Router::new()
                .route("/", get(page))
                .route("/events", get(events))
                .route("/latest", get(latest))
                .with_state(shared);
            match tokio::net::TcpListener::from_std(listener) {
                Ok(l) => {
                    if let Err(e) = axum::serve(l, app).await {
                        aeroident_report::note!("warning: live view: server stopped: {e}");
                    }
                }
                Err(e) => aeroident_report::note!("warning: live view: {e}"),
            }
        });
    })?;
    Ok(bound)
}

async fn page() -> Html<&'static str> {
    Html(PAGE)
}

fn lock(shared: &SharedLive) -> std::sync::MutexGuard<'_, aeroident_pipelines::live::LiveState> {
    shared.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Where one client's stream is.
struct Client {
    shared: SharedLive,
    cursor: Cursor,
    hello_sent: bool,
    first: bool,
    /// The final verdicts were sent: the `end` event follows.
    ending: bool,
    done: bool,
}

/// The next event of a client: an `update` per tick (with the `hello` once the names are
/// known), `end` after the final verdicts, then nothing.
async fn next(mut c: Client) -> Option<(Result<Event, Infallible>, Client)> {
    if c.done {
        return None;
    }
    if c.ending {
        // The page closes its stream on `end`; a stream merely closed would be reopened by
        // the browser and the history sent again.
        c.done = true;
        return Some((Ok(Event::default().event("end").data("{}")), c));
    }
    if !c.first {
        tokio::time::sleep(TICK).await;
    }
    c.first = false;
    let (data, concluded) = {
        let s = lock(&c.shared);
        if s.names().is_empty() {
            (None, s.concluded())
        } else {
            let hello = (!c.hello_sent).then(|| s.hello());
            let update = s.update(&mut c.cursor);
            let json = serde_json::json!({ "hello": hello, "update": update });
            (Some(json.to_string()), s.concluded())
        }
    };
    let event = match data {
        Some(d) => {
            c.hello_sent = true;
            Event::default().event("update").data(d)
        }
        None => Event::default().comment("waiting for the first sample"),
    };
    // The update holding the final verdicts is the last one.
    c.ending = concluded;
    Some((Ok(event), c))
}

async fn events(State(shared): State<SharedLive>) -> impl IntoResponse {
    let client = Client {
        shared,
        cursor: Cursor::default(),
        hello_sent: false,
        first: true,
        ending: false,
        done: false,
    };
    let stream = futures_util::stream::unfold(client, next);
    Sse::new(stream).keep_alive(KeepAlive::default())
}

async fn latest(State(shared): State<SharedLive>) -> impl IntoResponse {
    let s = lock(&shared);
    let body = serde_json::json!({
        "t": s.latest().map(|p| p.t),
        "seq": s.latest().map(|p| p.seq),
        "stats": s.stats(),
        "ended": s.ended(),
        "concluded": s.concluded(),
    });
    ([("content-type", "application/json")], body.to_string())
}
