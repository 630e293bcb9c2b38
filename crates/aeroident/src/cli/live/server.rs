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
//!
//! The server lives until [`LiveServer::close`]: closing wakes every stream, sends it the
//! state as it then is (the final verdicts once concluded, else the failure or interruption
//! the job recorded) and its `end`, and waits for each connection to finish writing. A
//! process that merely exited would cut the streams at whatever tick they were on, and a
//! client could miss the verdicts the page exists to show.

use aeroident_pipelines::live::{Cursor, SharedLive};
use axum::Router;
use axum::extract::State;
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse};
use axum::routing::get;
use std::convert::Infallible;
use std::net::SocketAddr;
use std::time::{Duration, Instant};
use tokio::sync::watch;

/// How often a client gets an update (10 Hz).
pub const TICK: Duration = Duration::from_millis(100);

const PAGE: &str = include_str!("page.html");

/// The running server of a live view ([`start`]): its address, and the handle that ends it.
#[derive(Debug)]
pub struct LiveServer {
    addr: SocketAddr,
    closing: watch::Sender<bool>,
    thread: std::thread::JoinHandle<()>,
}

impl LiveServer {
    /// The bound address (the port chosen when the asked one was 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Ends the view: every connected client gets the state as it is now and the `end`
    /// event, the listener stops accepting, and this waits at most `wait` for every
    /// connection to finish writing. Returns whether they all did (a client that stops
    /// reading can hold its connection open; the process then leaves it behind).
    pub fn close(self, wait: Duration) -> bool {
        // A send fails only when the server's thread has already ended.
        let _ = self.closing.send(true);
        let until = Instant::now() + wait;
        while !self.thread.is_finished() {
            if Instant::now() >= until {
                return false;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        self.thread.join().is_ok()
    }
}

/// Binds `addr` and serves the view of `shared` on a thread of its own until
/// [`LiveServer::close`].
///
/// # Errors
/// The address cannot be bound, or the thread or runtime cannot start.
pub fn start(addr: SocketAddr, shared: SharedLive) -> anyhow::Result<LiveServer> {
    let listener = std::net::TcpListener::bind(addr)?;
    listener.set_nonblocking(true)?;
    let bound = listener.local_addr()?;
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    let (closing, closed) = watch::channel(false);
    let thread = std::thread::Builder::new().name("live-view".into()).spawn(move || {
        runtime.block_on(serve(listener, Served { shared, closing: closed }));
    })?;
    Ok(LiveServer { addr: bound, closing, thread })
}

/// What every request sees: the view, and whether the server is closing.
#[derive(Clone)]
struct Served {
    shared: SharedLive,
    closing: watch::Receiver<bool>,
}

/// Serves until closing, then lets every open connection finish its response (axum's
/// graceful shutdown): the event streams end by themselves once they see the close.
async fn serve(listener: std::net::TcpListener, served: Served) {
    let mut closed = served.closing.clone();
    let app = Router::new()
        .route("/", get(page))
        .route("/events", get(events))
        .route("/latest", get(latest))
        .with_state(served);
    let l = match tokio::net::TcpListener::from_std(listener) {
        Ok(l) => l,
        Err(e) => return aeroident_report::note!("warning: live view: {e}"),
    };
    let shutdown = async move {
        // An error means the handle is gone: nobody can close it any more, so stop.
        let _ = closed.wait_for(|c| *c).await;
    };
    if let Err(e) = axum::serve(l, app).with_graceful_shutdown(shutdown).await {
        aeroident_report::note!("warning: live view: server stopped: {e}");
    }
}

async fn page() -> Html<&'static str> {
    Html(PAGE)
}

pub(super) fn lock(
    shared: &SharedLive,
) -> std::sync::MutexGuard<'_, aeroident_pipelines::live::LiveState> {
    shared.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Where one client's stream is.
struct Client {
    shared: SharedLive,
    closing: watch::Receiver<bool>,
    cursor: Cursor,
    hello_sent: bool,
    first: bool,
    /// The last update was sent (final verdicts, or the server closing): `end` follows.
    ending: bool,
    done: bool,
}

/// The next event of a client: an `update` per tick (with the `hello` once the names are
/// known), or at once when the server closes; `end` after the final verdicts or the close,
/// then nothing.
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
        tokio::select! {
            () = tokio::time::sleep(TICK) => {}
            _ = c.closing.wait_for(|closing| *closing) => {}
        }
    }
    c.first = false;
    let closing = *c.closing.borrow();
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
    // The update holding the final verdicts, or the state when the server closes, is the last.
    c.ending = concluded || closing;
    Some((Ok(event), c))
}

async fn events(State(served): State<Served>) -> impl IntoResponse {
    let client = Client {
        shared: served.shared,
        closing: served.closing,
        cursor: Cursor::default(),
        hello_sent: false,
        first: true,
        ending: false,
        done: false,
    };
    let stream = futures_util::stream::unfold(client, next);
    Sse::new(stream).keep_alive(KeepAlive::default())
}

async fn latest(State(served): State<Served>) -> impl IntoResponse {
    let s = lock(&served.shared);
    let body = serde_json::json!({
        "t": s.latest().map(|p| p.t),
        "seq": s.latest().map(|p| p.seq),
        "stats": s.stats(),
        "ended": s.ended(),
        "concluded": s.concluded(),
    });
    ([("content-type", "application/json")], body.to_string())
}

#[cfg(test)]
mod tests;
